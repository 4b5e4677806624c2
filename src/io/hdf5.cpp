#include "io/hdf5.hpp"


#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <type_traits>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace lb::h5 {
namespace {

struct Silence {
    Silence()
    {
        // Every file is closed (and checked) before it is renamed, so HDF5's exit-time
        // clean-up has nothing to do, except after a failed close (a full disk), where
        // HDF5 1.10 crashes closing the half-closed file again: skip it.
        H5dont_atexit();
        // HDF5 prints its own error stack to stderr; we report through exceptions.
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    }
};
const Silence g_silence;

class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : m_id(id), m_close(close) { }
    ~Handle()
    {
        if (m_id >= 0) m_close(m_id);
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    hid_t get() const { return m_id; }
    bool valid() const { return m_id >= 0; }
    /// Give up ownership (the caller closes the id).
    hid_t release()
    {
        const hid_t id = m_id;
        m_id = -1;
        return id;
    }

private:
    hid_t m_id;
    herr_t (*m_close)(hid_t);
};

std::string parent_of(const std::string& name)
{
    const auto pos = name.find_last_of('/');
    if (pos == std::string::npos || pos == 0) return "/";
    return name.substr(0, pos);
}

/// Largest dataset (in entries) a reader allocates for: 2^31 entries (16 GiB of
/// doubles), far beyond anything latentbench writes. A hostile or corrupt file can
/// declare any extent (a chunked dataset of 10^12 unwritten entries is a few bytes).
constexpr unsigned long long kMaxEntries = 1ULL << 31;
/// Largest fixed-length string attribute or dataset read (bytes).
constexpr size_t kMaxStringBytes = size_t(1) << 28;

std::string describe_dims(const std::vector<hsize_t>& dims)
{
    std::string s = "(";
    for (size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
    return s + (dims.size() == 1 ? ",)" : ")");
}

/// Why `space` does not hold exactly one value ("" if it does): a scalar dataspace or
/// a simple one of one element is accepted, so h5py's `attrs['dt'] = [1/30]` still reads.
std::string single_value_problem(hid_t space)
{
    switch (H5Sget_simple_extent_type(space)) {
    case H5S_SCALAR: return "";
    case H5S_NULL: return "holds no value (null dataspace)";
    case H5S_SIMPLE: {
        const int rank = H5Sget_simple_extent_ndims(space);
        if (rank < 0) return "has an unreadable dataspace";
        std::vector<hsize_t> dims(size_t(rank), 0);
        H5Sget_simple_extent_dims(space, dims.data(), nullptr);
        if (H5Sget_simple_extent_npoints(space) == 1) return "";
        return "must be a single value, found an array of shape " + describe_dims(dims);
    }
    default: return "has an unreadable dataspace";
    }
}

std::string class_name(H5T_class_t c)
{
    switch (c) {
    case H5T_INTEGER: return "an integer";
    case H5T_FLOAT: return "a floating-point number";
    case H5T_STRING: return "a string";
    case H5T_COMPOUND: return "a compound type";
    case H5T_ENUM: return "an enum";
    case H5T_ARRAY: return "an array type";
    case H5T_VLEN: return "a variable-length sequence";
    case H5T_REFERENCE: return "a reference";
    case H5T_OPAQUE: return "an opaque type";
    case H5T_BITFIELD: return "a bitfield";
    default: return "an unknown type";
    }
}

/// Read one string value (scalar or 1-element, fixed or variable length) from an
/// attribute or dataset whose type `ftype` has already been checked to be a string.
/// `read` is H5Aread or H5Dread bound to the object; returns false on failure.
template <typename Read>
bool read_one_string(hid_t ftype, Read read, std::string& out, std::string& problem)
{
    if (H5Tis_variable_str(ftype) > 0) {
        const hid_t mem = H5Tcopy(H5T_C_S1);
        H5Tset_size(mem, H5T_VARIABLE);
        H5Tset_cset(mem, H5Tget_cset(ftype));
        char* ptr = nullptr;
        const bool ok = read(mem, &ptr);
        H5Tclose(mem);
        if (!ok) return false;
        out = ptr ? ptr : "";
        H5free_memory(ptr);
        return true;
    }
    const size_t n = H5Tget_size(ftype);
    if (n == 0 || n > kMaxStringBytes) {
        problem = "has an implausible string length of " + std::to_string(n) + " bytes";
        return false;
    }
    std::string s(n + 1, '\0');  // room for a terminator HDF5 may not store
    if (!read(ftype, s.data())) return false;
    s.resize(std::strlen(s.c_str()));
    out = std::move(s);
    return true;
}

} // namespace

File::File(hid_t id, std::string path) : m_id(id), m_path(std::move(path)) { }

File::File(File&& other) noexcept : m_id(other.m_id), m_path(std::move(other.m_path))
{
    other.m_id = -1;
}

File& File::operator=(File&& other) noexcept
{
    if (this != &other) {
        if (m_id >= 0) H5Fclose(m_id);
        m_id = other.m_id;
        m_path = std::move(other.m_path);
        other.m_id = -1;
    }
    return *this;
}

File::~File()
{
    if (m_id >= 0) H5Fclose(m_id);
}

File File::create(const std::string& path)
{
    // The 1.8 file format or newer: the superblock and every object header carry a
    // checksum, so a damaged header is refused by HDF5 instead of being parsed (HDF5
    // 1.10.8 overruns its buffers parsing a bit-flipped version-1 header; the fuzz tests
    // under AddressSanitizer found it). h5py and HDF5 ≥ 1.8 read these files.
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_LATEST);
    const hid_t id = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
    if (id < 0) throw IoError("cannot create HDF5 file '" + path + "'");
    return File(id, path);
}

File File::open(const std::string& path, bool writable)
{
    if (!std::filesystem::exists(path)) {
        throw IoError("HDF5 file '" + path + "' does not exist");
    }
    if (H5Fis_hdf5(path.c_str()) <= 0) {
        throw IoError("'" + path + "' is not an HDF5 file (corrupt or wrong format)");
    }
    const hid_t id = H5Fopen(path.c_str(), writable ? H5F_ACC_RDWR : H5F_ACC_RDONLY, H5P_DEFAULT);
    if (id < 0) throw IoError("cannot open HDF5 file '" + path + "'");
    return File(id, path);
}

namespace {

/// Why a write failed, as far as the C library knows (HDF5 reports no cause).
std::string write_cause()
{
    if (errno == ENOSPC || errno == EDQUOT) return " (no space left on device)";
    return " (disk full or I/O error?)";
}

} // namespace

void File::fail(const std::string& what, const std::string& name) const
{
    throw IoError("HDF5 file '" + m_path + "', '" + name + "': " + what);
}

bool File::exists(const std::string& name) const
{
    // Check every path component, as H5Lexists requires its parents to exist.
    std::string partial;
    size_t start = name[0] == '/' ? 1 : 0;
    while (start <= name.size()) {
        size_t end = name.find('/', start);
        if (end == std::string::npos) end = name.size();
        partial += "/" + name.substr(start, end - start);
        if (H5Lexists(m_id, partial.c_str(), H5P_DEFAULT) <= 0) return false;
        start = end + 1;
    }
    return true;
}

void File::create_group(const std::string& group)
{
    if (group.empty() || group == "/" || exists(group)) return;
    create_group(parent_of(group));
    Handle g(H5Gcreate2(m_id, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!g.valid()) fail("cannot create group" + write_cause(), group);
}

void File::write_raw(const std::string& name, const std::vector<hsize_t>& dims, hid_t mem_type,
                     hid_t file_type, const void* data)
{
    create_group(parent_of(name));
    if (exists(name)) H5Ldelete(m_id, name.c_str(), H5P_DEFAULT);
    Handle space(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose);
    Handle set(H5Dcreate2(m_id, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                          H5P_DEFAULT),
               H5Dclose);
    if (!set.valid()) fail("cannot create dataset" + write_cause(), name);
    if (H5Dwrite(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
        fail("cannot write dataset" + write_cause(), name);
    }
}

void File::write(const std::string& name, const MatrixXd& m)
{
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    write_raw(name, {hsize_t(m.rows()), hsize_t(m.cols())}, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE,
              r.data());
}

void File::write(const std::string& name, const MatrixXf& m)
{
    const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    write_raw(name, {hsize_t(m.rows()), hsize_t(m.cols())}, H5T_NATIVE_FLOAT, H5T_IEEE_F32LE,
              r.data());
}

void File::write(const std::string& name, const VectorXd& v)
{
    write_raw(name, {hsize_t(v.size())}, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, v.data());
}

void File::write(const std::string& name, const MatrixXi& m)
{
    const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    write_raw(name, {hsize_t(m.rows()), hsize_t(m.cols())}, H5T_NATIVE_INT, H5T_STD_I32LE,
              r.data());
}

void File::write(const std::string& name, const VectorXi& v)
{
    write_raw(name, {hsize_t(v.size())}, H5T_NATIVE_INT, H5T_STD_I32LE, v.data());
}

void File::write_array(const std::string& name, const std::vector<hsize_t>& dims, const double* data)
{
    write_raw(name, dims, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data);
}

namespace {

// Strings are written fixed-length: their bytes sit in the object itself. Variable-
// length strings live in a global heap, and HDF5 1.10 loops forever reading a damaged
// one (found by the fuzz tests); only attributes too long for an object header
// (64 KiB) are still written variable-length. Readers accept both.
constexpr std::size_t kMaxFixedAttributeBytes = 32 * 1024;

/// A UTF-8 string's HDF5 type and the buffer to pass to H5Awrite/H5Dwrite.
class StringValue {
public:
    StringValue(const std::string& s, bool fixed) : m_type(H5Tcopy(H5T_C_S1), H5Tclose), m_ptr(s.c_str())
    {
        if (fixed) {
            H5Tset_size(m_type.get(), std::max<std::size_t>(s.size(), 1));  // "" as one NUL byte
            H5Tset_strpad(m_type.get(), H5T_STR_NULLPAD);
        } else {
            H5Tset_size(m_type.get(), H5T_VARIABLE);
        }
        H5Tset_cset(m_type.get(), H5T_CSET_UTF8);
        m_fixed = fixed;
    }
    hid_t type() const { return m_type.get(); }
    const void* buffer() const { return m_fixed ? static_cast<const void*>(m_ptr) : static_cast<const void*>(&m_ptr); }

private:
    Handle m_type;
    const char* m_ptr;
    bool m_fixed = true;
};

} // namespace

void File::write_string(const std::string& name, const std::string& s)
{
    create_group(parent_of(name));
    if (exists(name)) H5Ldelete(m_id, name.c_str(), H5P_DEFAULT);
    const StringValue value(s, /*fixed=*/true);
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle set(H5Dcreate2(m_id, name.c_str(), value.type(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
               H5Dclose);
    if (!set.valid()) fail("cannot create string dataset", name);
    if (H5Dwrite(set.get(), value.type(), H5S_ALL, H5S_ALL, H5P_DEFAULT, value.buffer()) < 0) {
        fail("cannot write string" + write_cause(), name);
    }
}

hid_t File::open_dataset(const std::string& name) const
{
    if (!exists(name)) fail("dataset missing", name);
    const hid_t id = H5Dopen2(m_id, name.c_str(), H5P_DEFAULT);
    if (id < 0) fail("cannot open dataset", name);
    return id;
}

std::vector<hsize_t> File::shape(const std::string& name) const
{
    Handle set(open_dataset(name), H5Dclose);
    return dataset_dims(set.get(), name);
}

std::vector<hsize_t> File::dataset_dims(hid_t set, const std::string& name) const
{
    Handle space(H5Dget_space(set), H5Sclose);
    if (!space.valid()) fail("cannot read shape", name);
    if (H5Sget_simple_extent_type(space.get()) == H5S_NULL) fail("dataset holds no value (null dataspace)", name);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 0) fail("cannot read shape", name);
    std::vector<hsize_t> dims(static_cast<size_t>(rank), 0);
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    unsigned long long entries = 1;
    for (const hsize_t d : dims) {
        if (d != 0 && entries > kMaxEntries / d) fail("shape " + describe_dims(dims) + " is too large to load", name);
        entries *= d;
    }
    if (entries > kMaxEntries) fail("shape " + describe_dims(dims) + " is too large to load", name);
    return dims;
}

void File::check_numeric(hid_t set, const std::string& name, bool integer) const
{
    Handle type(H5Dget_type(set), H5Tclose);
    const H5T_class_t c = H5Tget_class(type.get());
    if (c != H5T_INTEGER && c != H5T_FLOAT)
        fail("expected a numeric dataset, found " + class_name(c), name);
    // Reading floats into integers would truncate them (1.7 → 1) without a word.
    if (integer && c != H5T_INTEGER)
        fail("holds floating-point values; an index dataset must have an integer type", name);
}

namespace {
template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> read_2d(const File& f, hid_t id,
                                                              const std::vector<hsize_t>& dims,
                                                              hid_t mem_type, const std::string& name)
{
    const Index rows = dims.empty() ? 1 : Index(dims[0]);
    Index cols = 1;
    for (size_t i = 1; i < dims.size(); ++i) cols *= Index(dims[i]);
    Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r(rows, cols);
    if (r.size() > 0 && H5Dread(id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, r.data()) < 0) {
        throw IoError("HDF5 file '" + f.path() + "', '" + name + "': cannot read dataset");
    }
    return r;
}
} // namespace

template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> File::read_numeric(const std::string& name, size_t rank,
                                                                         hid_t mem_type) const
{
    Handle set(open_dataset(name), H5Dclose);
    const auto dims = dataset_dims(set.get(), name);
    if (dims.size() != rank)
        fail("expected a " + std::to_string(rank) + "-d dataset, found rank " + std::to_string(dims.size()), name);
    check_numeric(set.get(), name, std::is_integral_v<Scalar>);
    return read_2d<Scalar>(*this, set.get(), dims, mem_type, name);
}

MatrixXd File::read_matrix(const std::string& name) const { return read_numeric<double>(name, 2, H5T_NATIVE_DOUBLE); }

MatrixXf File::read_matrix_float(const std::string& name) const
{
    return read_numeric<float>(name, 2, H5T_NATIVE_FLOAT);
}

MatrixXi File::read_matrix_int(const std::string& name) const { return read_numeric<int>(name, 2, H5T_NATIVE_INT); }

VectorXd File::read_vector(const std::string& name) const { return read_numeric<double>(name, 1, H5T_NATIVE_DOUBLE); }

VectorXi File::read_vector_int(const std::string& name) const { return read_numeric<int>(name, 1, H5T_NATIVE_INT); }

std::vector<double> File::read_array(const std::string& name, std::vector<hsize_t>& dims) const
{
    Handle set(open_dataset(name), H5Dclose);
    dims = dataset_dims(set.get(), name);
    check_numeric(set.get(), name);
    size_t n = 1;
    for (auto d : dims) n *= size_t(d);
    std::vector<double> data(n);
    if (n > 0 && H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0) {
        fail("cannot read dataset", name);
    }
    return data;
}

std::string File::read_string(const std::string& name) const
{
    Handle set(open_dataset(name), H5Dclose);
    Handle space(H5Dget_space(set.get()), H5Sclose);
    const std::string problem = single_value_problem(space.get());
    if (!problem.empty()) fail("string dataset " + problem, name);
    Handle type(H5Dget_type(set.get()), H5Tclose);
    const H5T_class_t c = H5Tget_class(type.get());
    if (c != H5T_STRING) fail("expected a string dataset, found " + class_name(c), name);
    std::string s, why;
    const auto read = [&](hid_t mem, void* buf) {
        return H5Dread(set.get(), mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0;
    };
    if (!read_one_string(type.get(), read, s, why)) fail(why.empty() ? "cannot read string" : "string dataset " + why, name);
    return s;
}

namespace {
hid_t open_object(hid_t file, const std::string& path)
{
    return H5Oopen(file, path.c_str(), H5P_DEFAULT);
}
} // namespace

void File::set_attribute(const std::string& path, const std::string& key, const std::string& value)
{
    if (path != "/" && !exists(path)) create_group(path);
    Handle obj(open_object(m_id, path), H5Oclose);
    if (!obj.valid()) fail("cannot open object for attribute '" + key + "'", path);
    if (H5Aexists(obj.get(), key.c_str()) > 0) H5Adelete(obj.get(), key.c_str());
    const StringValue text(value, /*fixed=*/value.size() <= kMaxFixedAttributeBytes);
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle attr(H5Acreate2(obj.get(), key.c_str(), text.type(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!attr.valid() || H5Awrite(attr.get(), text.type(), text.buffer()) < 0) {
        fail("cannot write attribute '" + key + "'" + write_cause(), path);
    }
}

namespace {
template <typename T>
void set_scalar_attribute(hid_t file, const std::string& path, const std::string& key, T value,
                          hid_t mem_type, hid_t file_type, const File& f)
{
    Handle obj(open_object(file, path), H5Oclose);
    if (!obj.valid()) throw IoError("HDF5 file '" + f.path() + "', '" + path + "': cannot open object");
    if (H5Aexists(obj.get(), key.c_str()) > 0) H5Adelete(obj.get(), key.c_str());
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle attr(H5Acreate2(obj.get(), key.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                H5Aclose);
    if (!attr.valid() || H5Awrite(attr.get(), mem_type, &value) < 0) {
        throw IoError("HDF5 file '" + f.path() + "', '" + path + "': cannot write attribute '" + key + "'" + write_cause());
    }
}
} // namespace

void File::set_attribute(const std::string& path, const std::string& key, double value)
{
    if (path != "/" && !exists(path)) create_group(path);
    set_scalar_attribute(m_id, path, key, value, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, *this);
}

void File::set_attribute(const std::string& path, const std::string& key, long long value)
{
    if (path != "/" && !exists(path)) create_group(path);
    set_scalar_attribute(m_id, path, key, value, H5T_NATIVE_LLONG, H5T_STD_I64LE, *this);
}

bool File::has_attribute(const std::string& path, const std::string& key) const
{
    if (path != "/" && !exists(path)) return false;
    Handle obj(open_object(m_id, path), H5Oclose);
    return obj.valid() && H5Aexists(obj.get(), key.c_str()) > 0;
}

hid_t File::open_attribute(const std::string& path, const std::string& key, AttributeKind expected) const
{
    const std::string what = "attribute '" + key + "'";
    if (!has_attribute(path, key)) fail(what + " missing", path);
    Handle obj(open_object(m_id, path), H5Oclose);
    Handle attr(H5Aopen(obj.get(), key.c_str(), H5P_DEFAULT), H5Aclose);
    if (!attr.valid()) fail("cannot open " + what, path);
    Handle space(H5Aget_space(attr.get()), H5Sclose);
    const std::string problem = single_value_problem(space.get());
    if (!problem.empty()) fail(what + " " + problem, path);
    Handle type(H5Aget_type(attr.get()), H5Tclose);
    const H5T_class_t c = H5Tget_class(type.get());
    switch (expected) {
    case AttributeKind::string:
        if (c != H5T_STRING) fail(what + " must be a string, found " + class_name(c), path);
        break;
    case AttributeKind::integer:
        if (c != H5T_INTEGER) fail(what + " must be an integer, found " + class_name(c), path);
        break;
    case AttributeKind::number:
        if (c != H5T_INTEGER && c != H5T_FLOAT) fail(what + " must be a number, found " + class_name(c), path);
        break;
    }
    return attr.release();
}

std::string File::attribute_string(const std::string& path, const std::string& key) const
{
    Handle attr(open_attribute(path, key, AttributeKind::string), H5Aclose);
    Handle ftype(H5Aget_type(attr.get()), H5Tclose);
    std::string s, why;
    const auto read = [&](hid_t mem, void* buf) { return H5Aread(attr.get(), mem, buf) >= 0; };
    if (!read_one_string(ftype.get(), read, s, why)) {
        fail(why.empty() ? "cannot read attribute '" + key + "'" : "attribute '" + key + "' " + why, path);
    }
    return s;
}

double File::attribute_double(const std::string& path, const std::string& key) const
{
    Handle attr(open_attribute(path, key, AttributeKind::number), H5Aclose);
    double value = 0.0;
    if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &value) < 0) fail("cannot read attribute '" + key + "'", path);
    return value;
}

long long File::attribute_int(const std::string& path, const std::string& key) const
{
    Handle attr(open_attribute(path, key, AttributeKind::integer), H5Aclose);
    long long value = 0;
    if (H5Aread(attr.get(), H5T_NATIVE_LLONG, &value) < 0) fail("cannot read attribute '" + key + "'", path);
    return value;
}

std::vector<std::string> File::list(const std::string& group) const
{
    if (group != "/" && !exists(group)) fail("group missing", group);
    Handle g(H5Gopen2(m_id, group.c_str(), H5P_DEFAULT), H5Gclose);
    if (!g.valid()) fail("not a group", group);
    H5G_info_t info;
    if (H5Gget_info(g.get(), &info) < 0) fail("cannot list group", group);
    std::vector<std::string> names;
    for (hsize_t i = 0; i < info.nlinks; ++i) {
        const ssize_t n = H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0,
                                             H5P_DEFAULT);
        if (n < 0) fail("cannot list member " + std::to_string(i), group);
        std::string name(size_t(n), '\0');
        H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), size_t(n) + 1,
                           H5P_DEFAULT);
        names.push_back(name);
    }
    return names;
}

void File::flush() { H5Fflush(m_id, H5F_SCOPE_GLOBAL); }

void File::close()
{
    if (m_id < 0) return;
    const herr_t status = H5Fclose(m_id);
    m_id = -1;
    if (status < 0) throw IoError("cannot finish writing HDF5 file '" + m_path + "' (disk full or I/O error)");
}

void write_file_atomically(const std::string& path, const std::function<void(File&)>& fill)
{
    AtomicOutput out(path);
    File f = [&] {
        try {
            return File::create(out.temp_path());
        } catch (const IoError&) {
            throw IoError("cannot create HDF5 file '" + path + "': " + create_failure_reason(path));
        }
    }();
    try {
        fill(f);
        f.close();
    } catch (const IoError& e) {
        // Messages about the temporary would name a file that is about to be removed.
        std::string what = e.what();
        for (std::size_t at = what.find(out.temp_path()); at != std::string::npos; at = what.find(out.temp_path()))
            what.replace(at, out.temp_path().size(), path);
        throw IoError(what);
    }
    out.commit();
}

} // namespace lb::h5
