// The HDF5 wrapper's readers check an attribute's or dataset's dataspace and type
// before reading: array-valued attributes (h5py `attrs['dt'] = np.full(100, 1/30)`),
// wrong classes, null dataspaces and string arrays are IoErrors naming the file, the
// object and the attribute, never a read past a one-value buffer.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

std::string tmp_file(const std::string& name) { return testing::fresh_dir("hdf5_" + name) + "/f.h5"; }

/// Attach attribute `key` of type `type` and shape `dims` ({} = scalar, {0} with
/// null = a null dataspace) to the root group of `path`, written raw through the C API
/// the way another tool (h5py) would.
void raw_attribute(const std::string& path, const std::string& key, hid_t type, const std::vector<hsize_t>& dims,
                   const void* data, bool null_space = false)
{
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t space = null_space     ? H5Screate(H5S_NULL)
                        : dims.empty() ? H5Screate(H5S_SCALAR)
                                       : H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t attr = H5Acreate2(file, key.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(attr, 0);
    if (!null_space) {
        ASSERT_GE(H5Awrite(attr, type, data), 0);
    }
    H5Aclose(attr);
    H5Sclose(space);
    H5Fclose(file);
}

void raw_dataset(const std::string& path, const std::string& name, hid_t type, const std::vector<hsize_t>& dims,
                 const void* data)
{
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t space = dims.empty() ? H5Screate(H5S_SCALAR) : H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t set = H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(set, 0);
    ASSERT_GE(H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), 0);
    H5Dclose(set);
    H5Sclose(space);
    H5Fclose(file);
}

/// `read` throws an IoError whose message contains every one of `parts`.
void expect_io_error(const std::function<void()>& read, const std::vector<std::string>& parts)
{
    try {
        read();
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        for (const std::string& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
}

hid_t variable_string_type()
{
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    return t;
}

TEST(Hdf5Attributes, ArrayValuedNumberIsRefusedNamingFileObjectAndAttribute)
{
    const std::string path = tmp_file("array_attr");
    h5::File::create(path);
    const std::vector<double> hundred(100, 1.0 / 30.0);
    raw_attribute(path, "dt", H5T_NATIVE_DOUBLE, {100}, hundred.data());
    raw_attribute(path, "three", H5T_NATIVE_DOUBLE, {3}, hundred.data());
    const std::vector<long long> counts(100, 7);
    raw_attribute(path, "num_sequences", H5T_NATIVE_LLONG, {100}, counts.data());
    raw_attribute(path, "grid", H5T_NATIVE_LLONG, {2, 2}, counts.data());
    const h5::File f = h5::File::open(path);
    expect_io_error([&] { f.attribute_double("/", "dt"); }, {path, "'/'", "attribute 'dt'", "shape (100,)"});
    expect_io_error([&] { f.attribute_double("/", "three"); }, {path, "attribute 'three'", "shape (3,)"});
    expect_io_error([&] { f.attribute_int("/", "num_sequences"); }, {path, "attribute 'num_sequences'", "(100,)"});
    expect_io_error([&] { f.attribute_int("/", "grid"); }, {path, "attribute 'grid'", "(2, 2)"});
}

TEST(Hdf5Attributes, StringArraysAndNullSpacesAreRefused)
{
    const std::string path = tmp_file("string_array");
    h5::File::create(path);
    const hid_t vstr = variable_string_type();
    const char* many[100];
    for (auto& p : many) p = "solid";
    raw_attribute(path, "scene", vstr, {100}, many);
    raw_attribute(path, "empty", H5T_NATIVE_DOUBLE, {}, nullptr, /*null_space=*/true);
    H5Tclose(vstr);
    const h5::File f = h5::File::open(path);
    expect_io_error([&] { f.attribute_string("/", "scene"); }, {path, "attribute 'scene'", "(100,)"});
    expect_io_error([&] { f.attribute_double("/", "empty"); }, {path, "attribute 'empty'", "null dataspace"});
}

TEST(Hdf5Attributes, WrongClassIsRefused)
{
    const std::string path = tmp_file("wrong_class");
    {
        h5::File f = h5::File::create(path);
        f.set_attribute("/", "name", std::string("tiny"));
        f.set_attribute("/", "dt", 0.5);
        f.set_attribute("/", "count", 3LL);
    }
    const h5::File f = h5::File::open(path);
    expect_io_error([&] { f.attribute_double("/", "name"); }, {path, "attribute 'name'", "must be a number"});
    expect_io_error([&] { f.attribute_int("/", "name"); }, {path, "attribute 'name'", "must be an integer"});
    expect_io_error([&] { f.attribute_int("/", "dt"); }, {path, "attribute 'dt'", "must be an integer"});
    expect_io_error([&] { f.attribute_string("/", "dt"); }, {path, "attribute 'dt'", "must be a string"});
    // An integer reads as a double (h5py writes `attrs['dt'] = 1` as an integer).
    EXPECT_EQ(f.attribute_double("/", "count"), 3.0);
    expect_io_error([&] { f.attribute_double("/", "missing"); }, {path, "attribute 'missing' missing"});
}

TEST(Hdf5Attributes, OneElementArraysAndFixedLengthStringsAreAccepted)
{
    const std::string path = tmp_file("accepted");
    h5::File::create(path);
    const double dt = 0.25;
    raw_attribute(path, "dt", H5T_NATIVE_DOUBLE, {1}, &dt);
    const long long count = 4;
    raw_attribute(path, "count", H5T_NATIVE_LLONG, {1}, &count);
    // h5py's np.bytes_ attributes: fixed length, null-padded, no terminator stored.
    const hid_t fixed = H5Tcopy(H5T_C_S1);
    H5Tset_size(fixed, 5);
    H5Tset_strpad(fixed, H5T_STR_NULLPAD);
    raw_attribute(path, "scene", fixed, {}, "solid");
    const hid_t vstr = variable_string_type();
    const char* one[1] = {"cloth"};
    raw_attribute(path, "object", vstr, {1}, one);
    raw_dataset(path, "fixed_string", fixed, {}, "abcde");
    H5Tclose(fixed);
    H5Tclose(vstr);
    const h5::File f = h5::File::open(path);
    EXPECT_EQ(f.attribute_double("/", "dt"), 0.25);
    EXPECT_EQ(f.attribute_int("/", "count"), 4);
    EXPECT_EQ(f.attribute_string("/", "scene"), "solid");
    EXPECT_EQ(f.attribute_string("/", "object"), "cloth");
    EXPECT_EQ(f.read_string("fixed_string"), "abcde");
}

TEST(Hdf5Datasets, StringArraysAndNonNumericDatasetsAreRefused)
{
    const std::string path = tmp_file("datasets");
    {
        h5::File f = h5::File::create(path);
        f.write_string("text", "hello");
    }
    const hid_t vstr = variable_string_type();
    const char* many[4] = {"a", "b", "c", "d"};
    raw_dataset(path, "strings", vstr, {4}, many);
    H5Tclose(vstr);
    const h5::File f = h5::File::open(path);
    expect_io_error([&] { f.read_string("strings"); }, {path, "'strings'", "shape (4,)"});
    expect_io_error([&] { f.read_matrix("text"); }, {path, "'text'"});
    expect_io_error([&] { f.read_vector("text"); }, {path, "'text'"});
    std::vector<hsize_t> dims;
    expect_io_error([&] { f.read_array("strings", dims); }, {path, "'strings'", "expected a numeric dataset"});
    expect_io_error([&] { f.read_string("missing"); }, {path, "'missing'", "dataset missing"});
    EXPECT_EQ(f.read_string("text"), "hello");
}

TEST(Hdf5Datasets, HugeDeclaredExtentIsRefusedBeforeAllocating)
{
    // A chunked dataset may declare any extent without storing it: 2^40 × 3 doubles.
    const std::string path = tmp_file("huge");
    h5::File::create(path);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hsize_t dims[2] = {hsize_t(1) << 40, 3};
    const hsize_t chunk[2] = {16, 3};
    const hid_t space = H5Screate_simple(2, dims, nullptr);
    const hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(plist, 2, chunk);
    const hid_t set = H5Dcreate2(file, "huge", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, plist, H5P_DEFAULT);
    ASSERT_GE(set, 0);
    H5Dclose(set);
    H5Pclose(plist);
    H5Sclose(space);
    H5Fclose(file);
    const h5::File f = h5::File::open(path);
    expect_io_error([&] { f.read_matrix("huge"); }, {path, "'huge'", "too large"});
}

} // namespace
} // namespace lb
