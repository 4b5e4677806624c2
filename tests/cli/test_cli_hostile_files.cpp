// Hostile HDF5 files and option values through the CLI (issue 13, items 1-4 and 9):
// each used to crash (SIGSEGV, `free(): invalid pointer`) or run on garbage; now each
// exits 1 with a `latentbench: error:` line naming the file (or option) and the
// problem, and leaves no output or temporary file behind.
#include "lb_paths.hpp"
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "io/hdf5.hpp"
#include "support/cli_runner.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::write_file;
namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A fresh directory holding data.h5, the tiny scene simulated by the CLI.
std::string directory_with_dataset(const std::string& name)
{
    const std::string dir = fresh_dir("cli_hostile_" + name);
    write_file(dir + "/scene.toml", testing::kTinySceneToml);
    const auto sim = run_cli("simulate " + dir + "/scene.toml -o " + dir + "/data.h5");
    EXPECT_EQ(sim.exit_code, 0) << sim.output;
    return dir;
}

/// Copy of dir/data.h5 as dir/<name>.h5 with `mutate` applied.
std::string hostile_copy(const std::string& dir, const std::string& name, const std::function<void(h5::File&)>& mutate)
{
    const std::string path = dir + "/" + name + ".h5";
    fs::copy_file(dir + "/data.h5", path, fs::copy_options::overwrite_existing);
    h5::File f = h5::File::open(path, /*writable=*/true);
    mutate(f);
    return path;
}

/// Replace attribute `key` of object `object` with an n-element array, as h5py's
/// `obj.attrs[key] = np.full(n, value)` does.
void array_attribute(const h5::File& f, const std::string& object, const std::string& key, hsize_t n, hid_t type,
                     const void* data)
{
    const hid_t file = H5Fopen(f.path().c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t obj = H5Oopen(file, object.c_str(), H5P_DEFAULT);
    H5Adelete(obj, key.c_str());
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t attr = H5Acreate2(obj, key.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(H5Awrite(attr, type, data), 0);
    H5Aclose(attr);
    H5Sclose(space);
    H5Oclose(obj);
    H5Fclose(file);
}

/// `args` exits 1 with a `latentbench: error:` line containing every one of `parts`,
/// and leaves neither `output` nor any temporary file in its directory.
void expect_error(const std::string& args, const std::vector<std::string>& parts, const std::string& output = "")
{
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    const size_t at = r.output.find("latentbench: error:");
    ASSERT_NE(at, std::string::npos) << args << "\n" << r.output;
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    for (const std::string& p : parts) EXPECT_NE(line.find(p), std::string::npos) << args << "\n" << line;
    if (output.empty()) return;
    EXPECT_FALSE(fs::exists(output)) << args;
    for (const auto& entry : fs::directory_iterator(fs::path(output).parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
            << args << ": temporary file left behind: " << entry.path();
}

/// The commands that read a dataset, each on `path`.
void expect_every_reader_refuses(const std::string& dir, const std::string& path, const std::vector<std::string>& parts)
{
    std::vector<std::string> all = parts;
    all.push_back(path);
    const std::string out = dir + "/out.h5";
    expect_error("info " + path, all);
    expect_error("rollout " + path + " --method full_space --sequences all -o " + out, all, out);
    expect_error("fit --method linear_pca " + path + " -o " + out, all, out);
}

TEST(CliHostileFiles, ArrayValuedAttributes)
{
    const std::string dir = directory_with_dataset("attributes");
    const std::vector<double> hundred(100, 1.0 / 30.0);
    const std::vector<long long> counts(3, 1);
    const std::string dt = hostile_copy(dir, "dt_array", [&](h5::File& f) {
        array_attribute(f, "/", "dt", 100, H5T_NATIVE_DOUBLE, hundred.data());
    });
    expect_every_reader_refuses(dir, dt, {"attribute 'dt'", "(100,)"});
    const std::string dt3 = hostile_copy(dir, "dt_three", [&](h5::File& f) {
        array_attribute(f, "/", "dt", 3, H5T_NATIVE_DOUBLE, hundred.data());
    });
    expect_error("info " + dt3, {dt3, "attribute 'dt'", "(3,)"});
    const std::string count = hostile_copy(dir, "num_sequences_array", [&](h5::File& f) {
        array_attribute(f, "/", "num_sequences", 3, H5T_NATIVE_LLONG, counts.data());
    });
    expect_every_reader_refuses(dir, count, {"attribute 'num_sequences'", "(3,)"});
    const std::string train = hostile_copy(dir, "train_frames_array", [&](h5::File& f) {
        array_attribute(f, "sequences/0", "train_frames", 3, H5T_NATIVE_LLONG, counts.data());
    });
    expect_error("info " + train, {train, "'sequences/0'", "attribute 'train_frames'"});
    hid_t vstr = H5Tcopy(H5T_C_S1);
    H5Tset_size(vstr, H5T_VARIABLE);
    const char* names[100];
    for (auto& n : names) n = "tiny";
    const std::string scene = hostile_copy(dir, "scene_array", [&](h5::File& f) {
        array_attribute(f, "/", "scene", 100, vstr, names);
    });
    H5Tclose(vstr);
    expect_error("info " + scene, {scene, "attribute 'scene'", "(100,)"});
}

TEST(CliHostileFiles, DatasetShapes)
{
    const std::string dir = directory_with_dataset("shapes");
    const auto T = [](h5::File& f) { return Index(f.shape("sequences/0/positions")[0]); };
    const std::string newton = hostile_copy(dir, "newton_Tx0", [&](h5::File& f) {
        f.write("sequences/0/newton", MatrixXd(T(f), 0));
    });
    expect_every_reader_refuses(dir, newton, {"'sequences/0/newton'", "found 10×0"});
    const std::string params0 = hostile_copy(dir, "bc_params_Tx0", [&](h5::File& f) {
        f.write("sequences/0/bc_params", MatrixXd(T(f), 0));
    });
    expect_every_reader_refuses(dir, params0, {"'sequences/0/bc_params'", "found 10×0"});
    const std::string params500 = hostile_copy(dir, "bc_params_Tx500", [&](h5::File& f) {
        f.write("sequences/0/bc_params", MatrixXd(MatrixXd::Zero(T(f), 500)));
    });
    expect_error("info " + params500, {params500, "'sequences/0/bc_params'", "found 10×500"});
    const std::string zero = hostile_copy(dir, "zero_frames", [&](h5::File& f) {
        const Index N = Index(f.shape("rest_positions")[0]), B = Index(f.shape("bc/indices")[0]);
        f.write_array("sequences/0/positions", {0, hsize_t(N), 3}, nullptr);
        f.write_array("sequences/0/bc_positions", {0, hsize_t(B), 3}, nullptr);
        f.write("sequences/0/bc_params", MatrixXd(0, 6));
        f.write("sequences/0/newton", MatrixXd(0, 3));
        f.set_attribute("sequences/0", "train_frames", 0LL);
    });
    expect_every_reader_refuses(dir, zero, {"'sequences/0/positions'", "0 frames"});
    const std::string rest = hostile_copy(dir, "rest_0x3", [](h5::File& f) { f.write("rest_positions", MatrixXd(0, 3)); });
    expect_every_reader_refuses(dir, rest, {"'rest_positions'", "found 0×3"});
    const std::string train = hostile_copy(dir, "train_frames_past_end", [&](h5::File& f) {
        f.set_attribute("sequences/0", "train_frames", 11LL);
    });
    expect_every_reader_refuses(dir, train, {"'train_frames' = 11"});
}

TEST(CliHostileFiles, NonFiniteDatasetValues)
{
    const std::string dir = directory_with_dataset("nonfinite");
    const std::string params = hostile_copy(dir, "bc_params_nan", [](h5::File& f) {
        MatrixXd p = f.read_matrix("sequences/0/bc_params");
        p(3, 1) = kNaN;
        f.write("sequences/0/bc_params", p);
    });
    expect_every_reader_refuses(dir, params, {"'sequences/0/bc_params'", "non-finite"});
    const std::string gravity = hostile_copy(dir, "gravity_nan", [](h5::File& f) {
        f.write("gravity", VectorXd(Vector3d(0, 0, kNaN)));
    });
    expect_every_reader_refuses(dir, gravity, {"'gravity'", "non-finite"});
    const std::string dt = hostile_copy(dir, "dt_nan", [](h5::File& f) { f.set_attribute("/", "dt", kNaN); });
    expect_every_reader_refuses(dir, dt, {"'dt'"});
}

TEST(CliHostileFiles, RolloutFramesOutOfRange)
{
    const std::string dir = directory_with_dataset("frames");
    const std::string out = dir + "/roll.h5";
    for (const char* frames : {"1", "2", "-1", "4294967297", "10000001"}) {
        expect_error("rollout " + dir + "/data.h5 --method full_space --sequences all --frames=" + frames + " -o " + out,
                     {"--frames", "must be 0 (the whole sequence) or between 3"}, out);
    }
    const auto ok = run_cli("rollout " + dir + "/data.h5 --method full_space --sequences all --frames 3 -o " + out);
    EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

TEST(CliHostileFiles, SuiteFramesOutOfRange)
{
    const std::string dir = fresh_dir("cli_hostile_suite");
    for (const char* frames : {"4294967297", "1", "-3"}) {
        write_file(dir + "/suite.toml", std::string("name = \"x\"\n[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca\"\n"
                                                    "[[scenes]]\nscene = \"") +
                                            LB_SOURCE_DIR + "/experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n"
                                            "[evaluation]\nframes = " + frames + "\n");
        expect_error("run " + dir + "/suite.toml -o " + dir + "/run", {"suite.toml", "frames", "between 3"});
        EXPECT_FALSE(fs::exists(dir + "/run")) << frames;
    }
}

TEST(CliHostileFiles, AutoencoderWithHostileArchitectureOrWeights)
{
    const std::string dir = directory_with_dataset("autoencoder");
    const auto train = run_cli("train-ae " + dir + "/data.h5 -o " + dir + "/ae.h5 --epochs 2 --hidden 8 --pca 4 --latent 2");
    ASSERT_EQ(train.exit_code, 0) << train.output;
    const auto copy = [&](const std::string& name, const std::function<void(h5::File&)>& mutate) {
        const std::string path = dir + "/" + name + ".h5";
        fs::copy_file(dir + "/ae.h5", path, fs::copy_options::overwrite_existing);
        h5::File f = h5::File::open(path, /*writable=*/true);
        mutate(f);
        return path;
    };
    const std::string out = dir + "/out.h5";
    const std::string deep = copy("ae_deep", [](h5::File& f) {
        f.set_attribute("/", "decoder.architecture", std::string(200000, '['));
    });
    expect_error("fit --method latent_mlp " + dir + "/data.h5 --ae " + deep + " -o " + out,
                 {deep, "attribute 'decoder.architecture'", "nested deeper than 64"}, out);
    std::string weight;
    const std::string nan = copy("ae_nan_weight", [&](h5::File& f) {
        for (const std::string& name : f.list("/"))
            if (weight.empty() && name.rfind("decoder.", 0) == 0 && name.find("weight") != std::string::npos) weight = name;
        MatrixXd w = f.read_matrix(weight);
        w(0, 0) = kNaN;
        f.write(weight, w);
    });
    ASSERT_FALSE(weight.empty());
    expect_error("fit --method latent_mlp " + dir + "/data.h5 --ae " + nan + " -o " + out, {nan, weight, "non-finite"},
                 out);
}

// Index datasets stored as floats used to be truncated (1.4 → 1) and used; now every
// reader refuses them, naming the dataset.
TEST(CliHostileFiles, FloatValuedIndexDatasets)
{
    const std::string dir = directory_with_dataset("float_indices");
    const std::string elements = hostile_copy(dir, "elements_float", [](h5::File& f) {
        f.write("elements", MatrixXd(f.read_matrix_int("elements").cast<double>().array() + 0.4));
    });
    expect_every_reader_refuses(dir, elements, {"'elements'", "floating-point"});
    const std::string indices = hostile_copy(dir, "bc_indices_float", [](h5::File& f) {
        f.write("bc/indices", VectorXd(f.read_vector_int("bc/indices").cast<double>().array() + 0.4));
    });
    expect_every_reader_refuses(dir, indices, {"'bc/indices'", "floating-point"});
}

// A linear_pca artefact with a NaN variance used to load; one whose variances have the
// wrong length was reported as "shapes (mean 144, basis 144×3) do not match", naming
// neither the dataset nor a disagreement. Now each names 'linear_pca.variances'.
TEST(CliHostileFiles, LinearPcaVariances)
{
    const std::string dir = directory_with_dataset("pca_variances");
    const auto fit = run_cli("fit --method linear_pca " + dir + "/data.h5 -o " + dir + "/pca.h5 --set dim=2");
    ASSERT_EQ(fit.exit_code, 0) << fit.output;
    const auto copy = [&](const std::string& name, const std::function<void(h5::File&)>& mutate) {
        const std::string path = dir + "/" + name + ".h5";
        fs::copy_file(dir + "/pca.h5", path, fs::copy_options::overwrite_existing);
        h5::File f = h5::File::open(path, /*writable=*/true);
        mutate(f);
        return path;
    };
    const std::string out = dir + "/roll.h5";
    const auto roll = [&](const std::string& artefact) {
        return "rollout " + dir + "/data.h5 --integrator " + artefact + " --sequences all --frames 3 -o " + out;
    };
    const auto ok = run_cli(roll(dir + "/pca.h5"));
    ASSERT_EQ(ok.exit_code, 0) << ok.output;
    fs::remove(out);
    const std::string nan = copy("variances_nan", [](h5::File& f) {
        VectorXd v = f.read_vector("linear_pca.variances");
        v(1) = kNaN;
        f.write("linear_pca.variances", v);
    });
    expect_error(roll(nan), {nan, "'linear_pca.variances'", "not finite"}, out);
    const std::string negative = copy("variances_negative", [](h5::File& f) {
        VectorXd v = f.read_vector("linear_pca.variances");
        v(0) = -1.0;
        f.write("linear_pca.variances", v);
    });
    expect_error(roll(negative), {negative, "'linear_pca.variances'"}, out);
    const std::string longer = copy("variances_longer", [](h5::File& f) {
        f.write("linear_pca.variances", VectorXd(VectorXd::Ones(5)));
    });
    expect_error(roll(longer), {longer, "'linear_pca.variances'", "5 entries", "2 columns"}, out);
}

// Tetgen headers declaring more points or tetrahedra than the file or the mesh limits
// allow: exit 1 naming the file, the line and the count, under `simulate` and
// `simulate --check` (it used to be exit 2, `internal error: std::bad_alloc`).
TEST(CliHostileFiles, TetgenHeaderCounts)
{
    const std::string dir = fresh_dir("cli_hostile_tetgen");
    std::string scene = testing::kTinySceneToml;
    const std::string beam = "generator = \"tet_beam\"\nnx = 2\nny = 1\nnz = 1\nsize = [0.2, 0.1, 0.1]\n";
    scene.replace(scene.find(beam), beam.size(), "generator = \"tetgen\"\nnode = \"m.node\"\nele = \"m.ele\"\n");
    write_file(dir + "/scene.toml", scene);
    const std::string node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", ele = "1 4 0\n0 0 1 2 3\n";
    const std::string out = dir + "/out.h5";
    const auto check = [&](const std::string& node_text, const std::string& ele_text, const std::string& file,
                           const std::string& count) {
        write_file(dir + "/m.node", node_text);
        write_file(dir + "/m.ele", ele_text);
        for (const char* extra : {"", " --check"})
            expect_error("simulate " + dir + "/scene.toml -o " + out + extra, {dir + "/" + file + ":1:", count}, out);
    };
    check("100000000000 3 0 0\n0 0 0 0\n", ele, "m.node", "100000000000 points");
    check(node, "99999999999 4 0\n0 0 1 2 3\n", "m.ele", "99999999999 tetrahedra");
    check("1000000 3 0 0\n0 0 0 0\n", ele, "m.node", "1000000 points");
}

} // namespace
} // namespace lb
