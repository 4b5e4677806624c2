#pragma once
// Thin RAII wrapper over the HDF5 C API. Matrices are stored row-major as
// rows×cols datasets (what h5py/NumPy read naturally); intermediate groups are
// created on demand; every failure throws lb::IoError naming file and dataset.
#include <hdf5.h>

#include <functional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lb::h5 {

class File {
public:
    /// Create (truncate) a file for writing.
    static File create(const std::string& path);
    /// Open an existing file; throws IoError if missing or not HDF5.
    static File open(const std::string& path, bool writable = false);

    File(File&& other) noexcept;
    File& operator=(File&& other) noexcept;
    File(const File&) = delete;
    File& operator=(const File&) = delete;
    ~File();

    const std::string& path() const { return m_path; }
    bool exists(const std::string& name) const;

    void write(const std::string& name, const MatrixXd& m);
    void write(const std::string& name, const MatrixXf& m);
    void write(const std::string& name, const VectorXd& v);
    void write(const std::string& name, const MatrixXi& m);
    void write(const std::string& name, const VectorXi& v);
    /// n-d array of doubles, row-major (C order) `data` of product(dims) entries.
    void write_array(const std::string& name, const std::vector<hsize_t>& dims, const double* data);
    void write_string(const std::string& name, const std::string& s);

    MatrixXd read_matrix(const std::string& name) const;
    MatrixXf read_matrix_float(const std::string& name) const;
    VectorXd read_vector(const std::string& name) const;
    MatrixXi read_matrix_int(const std::string& name) const;
    VectorXi read_vector_int(const std::string& name) const;
    /// n-d array of doubles as a flat row-major vector; dims returned through `dims`.
    std::vector<double> read_array(const std::string& name, std::vector<hsize_t>& dims) const;
    std::string read_string(const std::string& name) const;
    std::vector<hsize_t> shape(const std::string& name) const;

    /// Attributes on a group or dataset ("/" for the file root). Overwrites.
    /// Readers accept exactly one value (scalar or 1-element dataspace) of the right
    /// kind: strings fixed or variable length; attribute_int an integer type;
    /// attribute_double an integer or floating type. Anything else is an IoError
    /// naming the file, the object and the attribute; nothing is read unchecked.
    void set_attribute(const std::string& path, const std::string& key, const std::string& value);
    void set_attribute(const std::string& path, const std::string& key, double value);
    void set_attribute(const std::string& path, const std::string& key, long long value);
    bool has_attribute(const std::string& path, const std::string& key) const;
    std::string attribute_string(const std::string& path, const std::string& key) const;
    double attribute_double(const std::string& path, const std::string& key) const;
    long long attribute_int(const std::string& path, const std::string& key) const;

    /// Names of the members of a group, sorted.
    std::vector<std::string> list(const std::string& group) const;
    /// Create a group (and parents) if it does not exist.
    void create_group(const std::string& group);

    void flush();
    /// Close now, checking the result: IoError naming the file if HDF5 could not write
    /// it out (a full disk). The destructor closes unchecked (error paths only).
    void close();

private:
    File(hid_t id, std::string path);
    hid_t m_id = -1;
    std::string m_path;

    void write_raw(const std::string& name, const std::vector<hsize_t>& dims, hid_t mem_type,
                   hid_t file_type, const void* data);
    hid_t open_dataset(const std::string& name) const;
    /// IoError unless dataset `set` has an integer or floating-point type (with `integer`:
    /// an integer type; indices stored as floats are refused, not truncated).
    void check_numeric(hid_t set, const std::string& name, bool integer = false) const;
    /// Extent of an open dataset, refusing null spaces and implausible sizes.
    std::vector<hsize_t> dataset_dims(hid_t set, const std::string& name) const;
    /// A numeric dataset of the given rank as a matrix (a vector for rank 1).
    template <typename Scalar>
    Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> read_numeric(const std::string& name, size_t rank,
                                                                       hid_t mem_type) const;
    enum class AttributeKind { string, integer, number };
    /// Open attribute `key` of `path` after checking that it holds one value (a scalar
    /// or 1-element dataspace) of the `expected` kind (number: integer or floating);
    /// IoError naming file, object and attribute otherwise. The caller closes the id.
    hid_t open_attribute(const std::string& path, const std::string& key, AttributeKind expected) const;
    [[noreturn]] void fail(const std::string& what, const std::string& name) const;
};

/// Write an HDF5 file atomically (io/atomic_file.hpp): `fill` writes into a temporary
/// beside `path`, which is then closed with its result checked (a full disk shows
/// there) and only then renamed onto `path`. On any error the temporary is removed,
/// `path` is untouched and the IoError names `path`.
void write_file_atomically(const std::string& path, const std::function<void(File&)>& fill);

} // namespace lb::h5
