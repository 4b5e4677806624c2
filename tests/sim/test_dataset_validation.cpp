// load_dataset validates every array's shape, range and finiteness against the
// others before anything indexes it: each mutation of a valid file below used to
// crash (zero frames, T×0 newton or bc_params, 0×3 rest positions), read out of
// bounds (bc_params T×1 or T×500, train_frames > T) or run on NaN; now each is an
// IoError naming the file and the dataset.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/hdf5.hpp"
#include "scene/scene.hpp"
#include "sim/dataset.hpp"
#include "support/cli_runner.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A valid dataset of the tiny scene (one 10-frame sequence), simulated once.
const std::string& good_dataset()
{
    static const std::string path = [] {
        const std::string p = testing::fresh_dir("dataset_validation") + "/good.h5";
        SimulateOptions options;
        options.progress = false;
        save_dataset(simulate_scene(load_scene_from_string(testing::kTinySceneToml, "tiny scene", "."), options), p);
        return p;
    }();
    return path;
}

struct Mutation {
    std::string name;
    std::function<void(h5::File&, Index N, Index T)> apply;
    std::vector<std::string> expected;  ///< substrings of the message besides the path
};

MatrixXd frames(Index T, Index count, double value = 0.0) { return MatrixXd::Constant(T, 3 * count, value); }

void write_frames(h5::File& f, const std::string& name, const MatrixXd& m)
{
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
    f.write_array(name, {hsize_t(m.rows()), hsize_t(m.cols() / 3), 3}, r.data());
}

void expect_rejected(const Mutation& m)
{
    const std::string path = fs::path(good_dataset()).parent_path().string() + "/" + m.name + ".h5";
    fs::copy_file(good_dataset(), path, fs::copy_options::overwrite_existing);
    {
        h5::File f = h5::File::open(path, /*writable=*/true);
        const Index N = Index(f.shape("rest_positions")[0]);
        const Index T = Index(f.shape("sequences/0/positions")[0]);
        m.apply(f, N, T);
    }
    try {
        load_dataset(path);
        ADD_FAILURE() << m.name << ": expected IoError";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << m.name << ": " << msg;
        for (const std::string& part : m.expected) EXPECT_NE(msg.find(part), std::string::npos) << m.name << ": " << msg;
    }
}

TEST(DatasetValidation, GoodDatasetLoads)
{
    const Dataset data = load_dataset(good_dataset());
    ASSERT_EQ(data.sequences.size(), 1u);
    EXPECT_EQ(data.sequences[0].num_frames(), 10);
    EXPECT_EQ(data.sequences[0].bc_params.cols(), Scene::kNumBcParams);
}

TEST(DatasetValidation, MeshArrays)
{
    const std::vector<Mutation> cases = {
        {"rest_0x3", [](h5::File& f, Index, Index) { f.write("rest_positions", MatrixXd(0, 3)); },
         {"'rest_positions'", "N ≥ 1", "found 0×3"}},
        {"rest_nan",
         [](h5::File& f, Index N, Index) {
             MatrixXd r = MatrixXd::Zero(N, 3);
             r(1, 2) = kNaN;
             f.write("rest_positions", r);
         },
         {"'rest_positions'", "non-finite"}},
        {"elements_range",
         [](h5::File& f, Index N, Index) { f.write("elements", MatrixXi(MatrixXi::Constant(2, 4, int(N)))); },
         {"'elements'", "out of range"}},
        {"elements_empty", [](h5::File& f, Index, Index) { f.write("elements", MatrixXi(0, 4)); },
         {"'elements'", "M ≥ 1"}},
        {"masses_short", [](h5::File& f, Index N, Index) { f.write("masses", VectorXd(VectorXd::Ones(N - 1))); },
         {"'masses'", "entries"}},
        {"masses_zero", [](h5::File& f, Index N, Index) { f.write("masses", VectorXd(VectorXd::Zero(N))); },
         {"'masses'", "positive"}},
        {"masses_nan",
         [](h5::File& f, Index N, Index) { f.write("masses", VectorXd(VectorXd::Constant(N, kNaN))); },
         {"'masses'", "non-finite"}},
        {"bc_range", [](h5::File& f, Index N, Index) { f.write("bc/indices", VectorXi(VectorXi::Constant(1, int(N)))); },
         {"'bc/indices'", "out of range"}},
        {"bc_empty", [](h5::File& f, Index, Index) { f.write("bc/indices", VectorXi(0)); }, {"'bc/indices'", "empty"}},
        {"object", [](h5::File& f, Index, Index) { f.set_attribute("/", "object", std::string("blob")); },
         {"'object'", "blob"}},
    };
    for (const Mutation& m : cases) expect_rejected(m);
}

TEST(DatasetValidation, PhysicsValues)
{
    const std::vector<Mutation> cases = {
        {"gravity_inf", [](h5::File& f, Index, Index) { f.write("gravity", VectorXd(Vector3d(0, 0, kInf))); },
         {"'gravity'", "non-finite"}},
        {"gravity_size", [](h5::File& f, Index, Index) { f.write("gravity", VectorXd(VectorXd::Zero(2))); },
         {"'gravity'", "3 entries"}},
        {"dt_nan", [](h5::File& f, Index, Index) { f.set_attribute("/", "dt", kNaN); }, {"'dt'", "positive and finite"}},
        {"dt_zero", [](h5::File& f, Index, Index) { f.set_attribute("/", "dt", 0.0); }, {"'dt'"}},
        {"youngs_inf", [](h5::File& f, Index, Index) { f.set_attribute("/", "youngs_modulus", kInf); },
         {"'youngs_modulus'"}},
        {"poisson", [](h5::File& f, Index, Index) { f.set_attribute("/", "poisson_ratio", 0.5); }, {"'poisson_ratio'"}},
        {"num_sequences_zero", [](h5::File& f, Index, Index) { f.set_attribute("/", "num_sequences", 0LL); },
         {"'num_sequences'"}},
        {"num_sequences_two", [](h5::File& f, Index, Index) { f.set_attribute("/", "num_sequences", 2LL); },
         {"sequences/1"}},
    };
    for (const Mutation& m : cases) expect_rejected(m);
}

TEST(DatasetValidation, SequenceArrays)
{
    const std::vector<Mutation> cases = {
        {"zero_frames",
         [](h5::File& f, Index N, Index) {
             write_frames(f, "sequences/0/positions", frames(0, N));
             write_frames(f, "sequences/0/bc_positions", frames(0, 3));
             f.write("sequences/0/bc_params", MatrixXd(0, 6));
             f.write("sequences/0/newton", MatrixXd(0, 3));
             f.set_attribute("sequences/0", "train_frames", 0LL);
         },
         {"'sequences/0/positions'", "0 frames", "at least 3"}},
        {"two_frames", [](h5::File& f, Index N, Index) { write_frames(f, "sequences/0/positions", frames(2, N)); },
         {"'sequences/0/positions'", "2 frames"}},
        {"positions_vertices",
         [](h5::File& f, Index N, Index T) { write_frames(f, "sequences/0/positions", frames(T, N + 1)); },
         {"'sequences/0/positions'", "found 10×"}},
        {"positions_nan",
         [](h5::File& f, Index N, Index T) { write_frames(f, "sequences/0/positions", frames(T, N, kNaN)); },
         {"'sequences/0/positions'", "non-finite"}},
        {"bc_positions_rows",
         [](h5::File& f, Index, Index T) {
             const Index B = Index(f.shape("bc/indices")[0]);
             write_frames(f, "sequences/0/bc_positions", frames(T - 1, B));
         },
         {"'sequences/0/bc_positions'"}},
        {"bc_positions_inf",
         [](h5::File& f, Index, Index T) {
             const Index B = Index(f.shape("bc/indices")[0]);
             write_frames(f, "sequences/0/bc_positions", frames(T, B, kInf));
         },
         {"'sequences/0/bc_positions'", "non-finite"}},
        {"bc_params_0", [](h5::File& f, Index, Index T) { f.write("sequences/0/bc_params", MatrixXd(T, 0)); },
         {"'sequences/0/bc_params'", "10×6", "found 10×0"}},
        {"bc_params_1",
         [](h5::File& f, Index, Index T) { f.write("sequences/0/bc_params", MatrixXd(MatrixXd::Zero(T, 1))); },
         {"'sequences/0/bc_params'", "found 10×1"}},
        {"bc_params_500",
         [](h5::File& f, Index, Index T) { f.write("sequences/0/bc_params", MatrixXd(MatrixXd::Zero(T, 500))); },
         {"'sequences/0/bc_params'", "found 10×500"}},
        {"bc_params_nan",
         [](h5::File& f, Index, Index T) { f.write("sequences/0/bc_params", MatrixXd(MatrixXd::Constant(T, 6, kNaN))); },
         {"'sequences/0/bc_params'", "non-finite"}},
        {"newton_0", [](h5::File& f, Index, Index T) { f.write("sequences/0/newton", MatrixXd(T, 0)); },
         {"'sequences/0/newton'", "found 10×0"}},
        {"newton_1", [](h5::File& f, Index, Index T) { f.write("sequences/0/newton", MatrixXd(MatrixXd::Zero(T, 1))); },
         {"'sequences/0/newton'", "found 10×1"}},
        {"train_frames_past_end",
         [](h5::File& f, Index, Index T) { f.set_attribute("sequences/0", "train_frames", (long long)T + 1); },
         {"'train_frames' = 11", "[0, T = 10]"}},
        {"train_frames_negative", [](h5::File& f, Index, Index) { f.set_attribute("sequences/0", "train_frames", -1LL); },
         {"'train_frames' = -1"}},
    };
    for (const Mutation& m : cases) expect_rejected(m);
}

TEST(DatasetValidation, SimulateRefusesSequencesTooShortToLoad)
{
    SimulateOptions options;
    options.progress = false;
    options.max_frames = 2;
    EXPECT_THROW(simulate_scene(load_scene_from_string(testing::kTinySceneToml, "tiny scene", "."), options),
                 ConfigError);
}

} // namespace
} // namespace lb
