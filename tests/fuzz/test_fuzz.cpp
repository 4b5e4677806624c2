// Fuzz tests (ctest label `fuzz`; issue 13): generated hostile inputs through the CLI.
//
// Scene and suite TOML files are mutated line by line and value by value; HDF5 files
// in every role (dataset, autoencoder, fitted method, rollout, training checkpoint)
// are mutated byte by byte (bit flips, truncation, overwritten blocks) and
// structurally (datasets removed, reshaped, retyped or poisoned with NaN, inf and
// extreme integers; attributes turned into arrays, retyped, removed or set to extreme
// values). Every case must end in exit status 0 or 1; status 1 must print a
// `latentbench: error:` line and leave neither the output nor a temporary file. A
// signal, another status or a hang fails the test, which names the seed, the case and
// the mutation and keeps the input under <build>/tests/tmp/fuzz_failures/.
//
// Environment: LB_FUZZ_SEED (default 20261130) and LB_FUZZ_SECONDS (time per role,
// default 15 s; each role runs at least kMinCases cases).
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/hdf5.hpp"
#include "nn/checkpoint.hpp"
#include "lb_paths.hpp"
#include "support/cli_runner.hpp"
#include "support/tiny_scene.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;
using testing::fresh_dir;
using testing::write_file;
using Rng = std::mt19937_64;

// The mutators' own HDF5 calls fail on purpose at times (a link already deleted):
// keep HDF5's error stack off the test output.
const bool g_hdf5_quiet = H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr) >= 0;

constexpr int kMinCases = 10;
constexpr double kCaseTimeout = 60.0;  // seconds; a hang is a failure
constexpr int kMaxReportedFailures = 5;

std::uint64_t fuzz_seed()
{
    const char* s = std::getenv("LB_FUZZ_SEED");
    return s ? std::strtoull(s, nullptr, 10) : 20261130ull;
}

double seconds_per_role()
{
    const char* s = std::getenv("LB_FUZZ_SECONDS");
    return s ? std::atof(s) : 15.0;
}

std::size_t pick(Rng& rng, std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); }

template <typename T>
const T& pick(Rng& rng, const std::vector<T>& v)
{
    return v[pick(rng, v.size())];
}

std::string read_text(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::vector<std::string> split_args(const std::string& args)
{
    std::vector<std::string> argv{LB_CLI_PATH};
    std::istringstream words(args);
    for (std::string w; words >> w;) argv.push_back(w);
    return argv;
}

// ---- The files every role starts from --------------------------------------------------

struct Corpus {
    std::string dir;
    std::string data, ae, mlp, pca, rollout;
    /// Training checkpoints of the autoencoder and of the latent MLP whose fingerprints match
    /// the fuzz commands' options, rewound to epoch 1 of 3: a mutant that keeps its
    /// fingerprint reaches the loader, and one the loader accepts trains on from its
    /// (mutated) weights, Adam moments and counters.
    std::string ae_checkpoint, fit_checkpoint;
    bool ok = false;
};

/// The options the fuzzed checkpoints were made with (the fingerprint covers them).
const char* const kAeCheckpointOptions = " --latent 2 --epochs 3 --hidden 8 --pca 4 --checkpoint-every 1";
const char* const kFitCheckpointOptions = " --set epochs=3 --set hidden=[8]";

/// Rewind a finished checkpoint to epoch 1, as one written by a run killed after it.
void rewind_checkpoint(const std::string& path)
{
    h5::File f = h5::File::open(path, /*writable=*/true);
    f.set_attribute("/", "epoch", 1LL);
    f.set_attribute("/", "best_epoch", std::min(1LL, f.attribute_int("/", "best_epoch")));
    f.set_attribute("/", "epochs_since_improvement", std::min(1LL, f.attribute_int("/", "epochs_since_improvement")));
    // The loss curve (nn/training_curve.hpp) as the killed run had it: its first epoch,
    // ending at the last loss, or the loader sets the checkpoint aside as inconsistent.
    for (const char* name : {"curve/train_loss", "curve/validation_loss"}) {
        if (!f.exists(name)) continue;
        const VectorXd first = f.read_vector(name).head(1);
        f.write(name, first);
        if (std::string(name) == "curve/train_loss") f.set_attribute("/", "last_loss", nn::exact_text(first(0)));
    }
}

/// The tiny scene simulated, an autoencoder, a latent MLP and a linear PCA fit, a
/// rollout and a training checkpoint: every HDF5 role, valid, made by the CLI.
const Corpus& corpus()
{
    static const Corpus c = [] {
        Corpus k;
        // One directory per test: ctest runs each test as its own process, two at a time, and
        // a shared directory let one process remove the files another was building.
        const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
        k.dir = fresh_dir(std::string("fuzz_corpus_") + (test ? test->name() : "main"));
        write_file(k.dir + "/scene.toml", testing::kTinySceneToml);
        k.data = k.dir + "/data.h5";
        k.ae = k.dir + "/ae.h5";
        k.mlp = k.dir + "/mlp.h5";
        k.pca = k.dir + "/pca.h5";
        k.rollout = k.dir + "/rollout.h5";
        k.ae_checkpoint = k.dir + "/ae_ck.h5";
        k.fit_checkpoint = k.dir + "/fit_ck.h5";
        const std::vector<std::string> steps = {
            "simulate " + k.dir + "/scene.toml -o " + k.data,
            "train-ae " + k.data + " -o " + k.ae + " --latent 2 --epochs 3 --hidden 8 --pca 4",
            "fit --method latent_mlp " + k.data + " --ae " + k.ae + " -o " + k.mlp + " --set epochs=2",
            "fit --method linear_pca " + k.data + " -o " + k.pca,
            "rollout " + k.data + " --integrator " + k.pca + " --sequences all -o " + k.rollout,
            "train-ae " + k.data + " -o " + k.dir + "/ae3.h5" + kAeCheckpointOptions + " --checkpoint " + k.ae_checkpoint,
            "fit --method latent_mlp " + k.data + " --ae " + k.ae + " -o " + k.dir + "/mlp3.h5" + kFitCheckpointOptions +
                " --checkpoint " + k.fit_checkpoint,
        };
        for (const std::string& s : steps) {
            const auto r = testing::run_cli("-q " + s);
            if (r.exit_code != 0) {
                ADD_FAILURE() << "building the fuzz corpus failed: " << s << "\n" << r.output;
                return k;
            }
        }
        rewind_checkpoint(k.ae_checkpoint);
        rewind_checkpoint(k.fit_checkpoint);
        k.ok = true;
        return k;
    }();
    return c;
}

// ---- One case ----------------------------------------------------------------------------

/// What became of a campaign's training checkpoints (counted from the log lines, so only
/// in a campaign that runs without -q).
struct CheckpointCounts {
    int cases = 0;
    int resumed = 0;  ///< the loader accepted the mutant and training went on from it
    int loader = 0;   ///< the mutant reached the loader (resumed, or refused there)
};

/// Runs cases for one role until its time is up, checking each outcome.
class Campaign {
public:
    /// @param quiet  run the CLI with -q (false: keep the log lines, to count checkpoints)
    explicit Campaign(const std::string& role, bool quiet = true)
        : m_role(role), m_dir(fresh_dir("fuzz_" + role)), m_quiet(quiet)
    {
        m_rng.seed(fuzz_seed() ^ std::hash<std::string>{}(role));
        m_start = std::chrono::steady_clock::now();
    }
    ~Campaign()
    {
        std::printf("[fuzz] %s: %d cases in %.1f s (seed %llu): %d exit 0, %d exit 1, %d failures\n", m_role.c_str(),
                    m_cases, elapsed(), (unsigned long long)fuzz_seed(), m_exit0, m_exit1, m_failures);
        if (!m_quiet)
            std::printf("[fuzz] %s: %d checkpoints reached the loader, %d were resumed\n", m_role.c_str(),
                        m_checkpoints.loader, m_checkpoints.resumed);
    }
    const CheckpointCounts& checkpoints() const { return m_checkpoints; }

    Rng& rng() { return m_rng; }
    const std::string& dir() const { return m_dir; }
    bool more() const
    {
        return m_failures < kMaxReportedFailures && (m_cases < kMinCases || elapsed() < seconds_per_role());
    }

    /// Run `args` (the output, if any, is `output`); `input` is the mutated file,
    /// `mutation` says what was done to it.
    void run(const std::string& args, const std::string& output, const std::string& input, const std::string& mutation)
    {
        ++m_cases;
        const std::vector<fs::path> before = listing();
        const std::string log = m_dir + "/output.txt";
        std::ofstream(log).close();
        ProcessOptions po{log, log, /*append_stdout=*/true};
        po.timeout_seconds = kCaseTimeout;
        const int status = run_process(split_args((m_quiet ? "-q " : "") + args), po);
        const std::string text = read_text(log);
        fs::remove(log);
        count_checkpoint(text);
        std::string problem;
        if (status == kProcessTimedOut) {
            problem = "hung (killed after " + std::to_string(int(kCaseTimeout)) + " s)";
        } else if (status == 0) {
            ++m_exit0;
        } else if (status == 1) {
            ++m_exit1;
            if (text.find("latentbench: error:") == std::string::npos) problem = "exit 1 without a `latentbench: error:` line";
            else if (!output.empty() && fs::exists(output)) problem = "exit 1 but the output " + output + " was written";
        } else {
            problem = status > 128 ? "killed by signal " + std::to_string(status - 128) : "exit status " + std::to_string(status);
        }
        for (const fs::path& p : listing()) {
            if (p.filename().string().find(".tmp-") != std::string::npos)
                problem += (problem.empty() ? "" : "; ") + std::string("temporary file left behind: ") + p.string();
        }
        if (!problem.empty()) fail(args, input, mutation, problem, text);
        // Back to the state before the case: outputs and set-aside files go.
        for (const fs::path& p : listing()) {
            if (std::find(before.begin(), before.end(), p) == before.end()) fs::remove_all(p);
        }
    }

private:
    std::string m_role, m_dir;
    bool m_quiet = true;
    CheckpointCounts m_checkpoints;
    Rng m_rng;
    std::chrono::steady_clock::time_point m_start;
    int m_cases = 0, m_exit0 = 0, m_exit1 = 0, m_failures = 0;

    /// A checkpoint refused before the loader: by its format or its fingerprint.
    static bool refused_by_fingerprint(const std::string& reason)
    {
        for (const char* part : {"its options differ", "its data differ", "its network differ", "its autoencoder differ",
                                 "its physics differ", "fingerprint", "of this version"})
            if (reason.find(part) != std::string::npos) return true;
        return false;
    }
    void count_checkpoint(const std::string& text)
    {
        ++m_checkpoints.cases;
        if (text.find("resuming from checkpoint") != std::string::npos) {
            ++m_checkpoints.resumed;
            ++m_checkpoints.loader;
            return;
        }
        const std::size_t at = text.find(" not resumed: ");
        if (at != std::string::npos && !refused_by_fingerprint(text.substr(at, text.find('\n', at) - at)))
            ++m_checkpoints.loader;
    }
    double elapsed() const
    {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }
    std::vector<fs::path> listing() const
    {
        std::vector<fs::path> v;
        for (const auto& e : fs::directory_iterator(m_dir)) v.push_back(e.path());
        return v;
    }
    void fail(const std::string& args, const std::string& input, const std::string& mutation,
              const std::string& problem, const std::string& text)
    {
        ++m_failures;
        const fs::path keep = fs::path(LB_TEST_TMP_DIR) / "fuzz_failures" /
                              (m_role + "_" + std::to_string(m_cases) + fs::path(input).extension().string());
        fs::create_directories(keep.parent_path());
        std::error_code ec;
        fs::copy_file(input, keep, fs::copy_options::overwrite_existing, ec);
        ADD_FAILURE() << m_role << " case " << m_cases << " (LB_FUZZ_SEED=" << fuzz_seed() << "): " << problem
                      << "\n  mutation: " << mutation << "\n  command: latentbench " << args
                      << "\n  input kept as: " << keep.string() << "\n  output:\n"
                      << text.substr(0, 3000);
    }
};

// ---- TOML mutations -------------------------------------------------------------------------

const std::vector<std::string> kHostileValues = {
    "-1", "0", "1", "2", "3", "99999", "4294967298", "9223372036854775807", "-9223372036854775808", "1e308",
    "-1e308", "nan", "inf", "-inf", "1e-320", "0.5", "\"\"", "\"../escaped\"", "\"x';touch PWNED;echo '\"",
    "\"a b\"", "true", "false", "[]", "[1, 2]", "[1e308, nan, 0]", "[[]]", "{}", "{ a = 1 }", "\"/dev/null\"",
    "\"nonexistent.toml\"", "[\"x\", 1]", "1970-01-01"};

std::vector<std::string> lines_of(const std::string& text)
{
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    return lines;
}

std::string join(const std::vector<std::string>& lines)
{
    std::string s;
    for (const std::string& l : lines) s += l + "\n";
    return s;
}

/// One or more random edits; `what` describes them.
std::string mutate_toml(Rng& rng, std::string text, std::string& what)
{
    const int edits = 1 + int(pick(rng, 3));
    for (int e = 0; e < edits; ++e) {
        std::vector<std::string> lines = lines_of(text);
        if (lines.empty()) lines.push_back("");
        const std::size_t i = pick(rng, lines.size());
        switch (pick(rng, 8)) {
            case 0:
            case 1:
            case 2: {  // a value replaced by a hostile one
                const std::size_t eq = lines[i].find('=');
                if (eq == std::string::npos) break;
                const std::string& v = pick(rng, kHostileValues);
                what += "line " + std::to_string(i + 1) + " value -> " + v + "; ";
                lines[i] = lines[i].substr(0, eq + 1) + " " + v;
                break;
            }
            case 3:
                what += "line " + std::to_string(i + 1) + " deleted; ";
                lines.erase(lines.begin() + std::ptrdiff_t(i));
                break;
            case 4:
                what += "line " + std::to_string(i + 1) + " duplicated; ";
                lines.insert(lines.begin() + std::ptrdiff_t(i), lines[i]);
                break;
            case 5: {
                const std::size_t j = pick(rng, lines.size());
                what += "lines " + std::to_string(i + 1) + " and " + std::to_string(j + 1) + " swapped; ";
                std::swap(lines[i], lines[j]);
                break;
            }
            case 6: {  // a character replaced (any byte but NUL)
                if (lines[i].empty()) break;
                const std::size_t at = pick(rng, lines[i].size());
                const char c = char(1 + pick(rng, 255));
                what += "line " + std::to_string(i + 1) + " byte " + std::to_string(at) + " -> " +
                        std::to_string(int((unsigned char)c)) + "; ";
                lines[i][at] = c;
                break;
            }
            case 7: {  // truncated
                const std::string all = join(lines);
                const std::size_t at = pick(rng, all.size() + 1);
                what += "truncated at byte " + std::to_string(at) + "; ";
                text = all.substr(0, at);
                continue;
            }
        }
        text = join(lines);
    }
    return text;
}

// ---- HDF5 mutations -------------------------------------------------------------------------

struct H5Objects {
    std::vector<std::string> datasets, groups;  // groups include "/"
};

void collect(hid_t file, const std::string& group, H5Objects& out)
{
    out.groups.push_back(group);
    const hid_t g = H5Gopen2(file, group.c_str(), H5P_DEFAULT);
    if (g < 0) return;
    H5G_info_t info;
    if (H5Gget_info(g, &info) < 0) {
        H5Gclose(g);
        return;
    }
    for (hsize_t i = 0; i < info.nlinks; ++i) {
        char name[512];
        if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0) continue;
        const std::string path = (group == "/" ? "/" : group + "/") + name;
        const hid_t obj = H5Oopen(file, path.c_str(), H5P_DEFAULT);
        if (obj < 0) continue;
        const H5I_type_t type = H5Iget_type(obj);
        H5Oclose(obj);
        if (type == H5I_GROUP) collect(file, path, out);
        if (type == H5I_DATASET) out.datasets.push_back(path);
    }
    H5Gclose(g);
}

herr_t attribute_name(hid_t, const char* name, const H5A_info_t*, void* data)
{
    static_cast<std::vector<std::string>*>(data)->push_back(name);
    return 0;
}

std::vector<std::pair<std::string, std::string>> attributes(hid_t file, const H5Objects& objects)
{
    std::vector<std::pair<std::string, std::string>> all;
    std::vector<std::string> objs = objects.groups;
    objs.insert(objs.end(), objects.datasets.begin(), objects.datasets.end());
    for (const std::string& o : objs) {
        std::vector<std::string> names;
        H5Aiterate_by_name(file, o.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr, attribute_name, &names, H5P_DEFAULT);
        for (const std::string& n : names) all.emplace_back(o, n);
    }
    return all;
}

/// A numeric dataset's values as doubles and its extent; false if not numeric.
bool read_doubles(hid_t file, const std::string& name, std::vector<hsize_t>& dims, std::vector<double>& values,
                  bool& integer)
{
    const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    if (set < 0) return false;
    const hid_t type = H5Dget_type(set);
    const H5T_class_t cls = H5Tget_class(type);
    H5Tclose(type);
    const hid_t space = H5Dget_space(set);
    const int rank = H5Sget_simple_extent_ndims(space);
    dims.assign(std::size_t(std::max(rank, 0)), 0);
    if (rank > 0) H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    H5Sclose(space);
    if (cls != H5T_INTEGER && cls != H5T_FLOAT) {
        H5Dclose(set);
        return false;
    }
    integer = cls == H5T_INTEGER;
    hsize_t n = 1;
    for (hsize_t d : dims) n *= d;
    values.assign(n, 0.0);
    const bool ok = n == 0 || H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) >= 0;
    H5Dclose(set);
    return ok;
}

void write_doubles(hid_t file, const std::string& name, const std::vector<hsize_t>& dims,
                   const std::vector<double>& values, bool integer)
{
    H5Ldelete(file, name.c_str(), H5P_DEFAULT);
    const hid_t space = H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t type = integer ? H5T_STD_I32LE : H5T_IEEE_F64LE;
    const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    const hid_t set = H5Dcreate2(file, name.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    if (set >= 0 && !values.empty()) {
        if (integer) {
            std::vector<int> ints(values.size());
            for (std::size_t i = 0; i < values.size(); ++i)
                ints[i] = std::isfinite(values[i]) ? int(std::clamp(values[i], -2147483648.0, 2147483647.0)) : -1;
            H5Dwrite(set, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, ints.data());
        } else {
            H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
        }
    }
    if (set >= 0) H5Dclose(set);
    H5Pclose(lcpl);
    H5Sclose(space);
}

std::string dims_text(const std::vector<hsize_t>& dims)
{
    std::string s = "(";
    for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? "x" : "") + std::to_string(dims[i]);
    return s + ")";
}

void write_string_attribute(hid_t obj, const std::string& key, const std::string& value)
{
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, std::max<std::size_t>(value.size(), 1));
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(obj, key.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
    if (attr >= 0) {
        H5Awrite(attr, type, value.c_str());
        H5Aclose(attr);
    }
    H5Sclose(space);
    H5Tclose(type);
}

void write_number_attribute(hid_t obj, const std::string& key, hid_t mem_type, hid_t file_type, hsize_t n,
                            const void* data)
{
    const hid_t space = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
    const hid_t attr = H5Acreate2(obj, key.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT);
    if (attr >= 0) {
        H5Awrite(attr, mem_type, data);
        H5Aclose(attr);
    }
    H5Sclose(space);
}

/// A structural edit through the HDF5 library; returns its description.
std::string mutate_structure(Rng& rng, const std::string& path)
{
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (file < 0) return "(file would not open for editing)";
    H5Objects objects;
    collect(file, "/", objects);
    std::string what;
    const std::size_t kind = pick(rng, 6);
    if (kind <= 2 && !objects.datasets.empty()) {
        const std::string name = pick(rng, objects.datasets);
        std::vector<hsize_t> dims;
        std::vector<double> v;
        bool integer = false;
        if (kind == 0 || !read_doubles(file, name, dims, v, integer)) {
            if (pick(rng, 2) == 0) {
                H5Ldelete(file, name.c_str(), H5P_DEFAULT);
                what = "dataset " + name + " deleted";
            } else {
                H5Ldelete(file, name.c_str(), H5P_DEFAULT);
                const hid_t space = H5Screate(H5S_SCALAR);
                const hid_t type = H5Tcopy(H5T_C_S1);
                H5Tset_size(type, 8);
                const hid_t set = H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
                if (set >= 0) {
                    H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, "garbage");
                    H5Dclose(set);
                }
                H5Tclose(type);
                H5Sclose(space);
                what = "dataset " + name + " replaced by a string";
            }
        } else if (kind == 1) {  // reshaped
            const hsize_t r = dims.empty() ? 1 : dims[0], c = dims.size() > 1 ? dims[1] : 1;
            const std::vector<std::vector<hsize_t>> shapes = {
                {0, c}, {1, c}, {r + 1, c}, {r > 0 ? r - 1 : 0, c}, {c, r}, {r * c}, {r, c, 2}, {r, 0}, {r, c + 1}, {0}, {1}};
            const std::vector<hsize_t> nd = pick(rng, shapes);
            hsize_t n = 1;
            for (hsize_t d : nd) n *= d;
            std::vector<double> nv(n);
            for (hsize_t i = 0; i < n; ++i) nv[i] = v.empty() ? 0.0 : v[i % v.size()];
            write_doubles(file, name, nd, nv, integer);
            what = "dataset " + name + " " + dims_text(dims) + " reshaped to " + dims_text(nd);
        } else {  // poisoned values
            const std::vector<double> specials = {std::numeric_limits<double>::quiet_NaN(),
                                                  std::numeric_limits<double>::infinity(),
                                                  -std::numeric_limits<double>::infinity(), 1e300, -1e300, -1.0,
                                                  0.0, 2147483647.0, -2147483648.0, 1e9};
            const double x = pick(rng, specials);
            const std::size_t count = v.empty() ? 0 : 1 + pick(rng, std::min<std::size_t>(v.size(), 4));
            for (std::size_t k = 0; k < count; ++k) v[pick(rng, v.size())] = x;
            write_doubles(file, name, dims, v, integer);
            what = "dataset " + name + ": " + std::to_string(count) + " entries set to " + std::to_string(x);
        }
    } else if (kind <= 4) {
        const auto attrs = attributes(file, objects);
        if (attrs.empty()) {
            what = "(no attributes)";
        } else {
            const auto& [object, key] = pick(rng, attrs);
            const hid_t obj = H5Oopen(file, object.c_str(), H5P_DEFAULT);
            H5Adelete(obj, key.c_str());
            what = "attribute " + object + ":" + key;
            switch (pick(rng, 5)) {
                case 0:
                    what += " deleted";
                    break;
                case 1: {
                    const hsize_t n = pick(rng, 2) ? 2 : 100;
                    std::vector<double> a(n, 1.0 / 30.0);
                    write_number_attribute(obj, key, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, a.data());
                    what += " -> array of " + std::to_string(n) + " doubles";
                    break;
                }
                case 2: {
                    const std::string s = pick(rng, std::vector<std::string>{"x", "{", "[[[[", "nan", "-1", "1e999"});
                    write_string_attribute(obj, key, s);
                    what += " -> string '" + s + "'";
                    break;
                }
                case 3: {
                    const long long x = pick(rng, std::vector<long long>{-1, 0, 2147483648LL, 1LL << 62,
                                                                         std::numeric_limits<long long>::min()});
                    write_number_attribute(obj, key, H5T_NATIVE_LLONG, H5T_STD_I64LE, 1, &x);
                    what += " -> integer " + std::to_string(x);
                    break;
                }
                case 4: {
                    const double x = pick(rng, std::vector<double>{std::numeric_limits<double>::quiet_NaN(),
                                                                   std::numeric_limits<double>::infinity(), -1.0,
                                                                   1e308, 0.0});
                    write_number_attribute(obj, key, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 1, &x);
                    what += " -> double " + std::to_string(x);
                    break;
                }
            }
            H5Oclose(obj);
        }
    } else {  // an unexpected member
        const std::string group = pick(rng, objects.groups);
        const std::string name = (group == "/" ? "/" : group + "/") + "fuzz_extra";
        std::vector<double> v(6, 1.0);
        write_doubles(file, name, {2, 3}, v, false);
        what = "extra dataset " + name;
    }
    H5Fclose(file);
    return what;
}

/// A byte-level edit of the file on disk; returns its description.
std::string mutate_bytes(Rng& rng, const std::string& path)
{
    std::string bytes = read_text(path);
    if (bytes.empty()) return "(empty file)";
    std::string what;
    switch (pick(rng, 4)) {
        case 0: {  // bit flips, half of the time in the first 4 KiB (superblock, root metadata)
            const int flips = 1 + int(pick(rng, 16));
            const std::size_t span = pick(rng, 2) ? std::min<std::size_t>(bytes.size(), 4096) : bytes.size();
            for (int k = 0; k < flips; ++k) bytes[pick(rng, span)] ^= char(1u << pick(rng, 8));
            what = std::to_string(flips) + " bit flips in the first " + std::to_string(span) + " bytes";
            break;
        }
        case 1: {
            const std::size_t at = pick(rng, bytes.size());
            bytes.resize(at);
            what = "truncated to " + std::to_string(at) + " bytes";
            break;
        }
        case 2: {
            const std::size_t at = pick(rng, bytes.size());
            const std::size_t n = std::min(bytes.size() - at, std::size_t(64) << pick(rng, 7));
            const char fill = pick(rng, 2) ? '\0' : char(0xff);
            std::fill_n(bytes.begin() + std::ptrdiff_t(at), n, fill);
            what = std::to_string(n) + " bytes at " + std::to_string(at) + " set to " + (fill ? "0xff" : "0");
            break;
        }
        case 3: {
            const std::size_t at = pick(rng, bytes.size());
            const std::size_t n = std::min(bytes.size() - at, std::size_t(1) + pick(rng, 256));
            for (std::size_t k = 0; k < n; ++k) bytes[at + k] = char(pick(rng, 256));
            what = std::to_string(n) + " random bytes at " + std::to_string(at);
            break;
        }
    }
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    return what;
}

/// Copy `source` to `target` and mutate it (structurally or byte-wise).
std::string hostile_copy(Rng& rng, const std::string& source, const std::string& target)
{
    fs::copy_file(source, target, fs::copy_options::overwrite_existing);
    // Structural edits first: they go through the HDF5 library, which must not be handed
    // a file already damaged byte-wise (it can loop forever on one, in this process).
    std::string what;
    const int structural = int(pick(rng, 3));  // 0, 1 or 2
    const bool bytes = structural == 0 || pick(rng, 3) == 0;
    for (int e = 0; e < structural; ++e) what += (what.empty() ? "" : "; ") + mutate_structure(rng, target);
    if (bytes) what += (what.empty() ? "" : "; ") + mutate_bytes(rng, target);
    return what;
}

// ---- The roles ------------------------------------------------------------------------------

const std::string kSource = LB_SOURCE_DIR;

void fuzz_toml(const std::string& role, const std::vector<std::string>& sources,
               const std::function<std::string(const std::string& source, const std::string& mutated)>& command)
{
    Campaign c(role);
    // Suites name scenes relative to themselves ("scenes/cloth.toml").
    fs::create_directory_symlink(kSource + "/experiments/scenes", c.dir() + "/scenes");
    std::vector<std::string> texts;
    for (const std::string& s : sources) texts.push_back(read_text(s));
    while (c.more()) {
        const std::size_t which = pick(c.rng(), sources.size());
        std::string what = fs::path(sources[which]).filename().string() + ": ";
        const std::string mutated = c.dir() + "/case" + fs::path(sources[which]).extension().string();
        write_file(mutated, mutate_toml(c.rng(), texts[which], what));
        c.run(command(sources[which], mutated), "", mutated, what);
    }
}

CheckpointCounts fuzz_hdf5(const std::string& role, const std::vector<std::string>& sources,
                           const std::function<std::string(const std::string& source, const std::string& mutated,
                                                           const std::string& out)>& command,
                           bool quiet = true)
{
    if (!corpus().ok) {
        ADD_FAILURE() << "no fuzz corpus";
        return {};
    }
    Campaign c(role, quiet);
    while (c.more()) {
        const std::string& source = pick(c.rng(), sources);
        const std::string mutated = c.dir() + "/case.h5";
        const std::string out = c.dir() + "/out.h5";
        const std::string what = fs::path(source).filename().string() + ": " + hostile_copy(c.rng(), source, mutated);
        c.run(command(source, mutated, out), out, mutated, what);
    }
    return c.checkpoints();
}

TEST(Fuzz, SceneToml)
{
    const std::string scenes = kSource + "/experiments/scenes/";
    fuzz_toml("scene_toml",
              {scenes + "cloth.toml", scenes + "cantilever.toml", scenes + "rods_translate.toml",
               scenes + "bunny_ears.toml"},
              [](const std::string&, const std::string& mutated) {
                  return "simulate " + mutated + " --variant small --check";
              });
}

TEST(Fuzz, SuiteToml)
{
    const std::string ex = kSource + "/experiments/";
    const std::string run_dir = fresh_dir("fuzz_suite_run");
    fuzz_toml("suite_toml", {ex + "quickstart.toml", ex + "ablations.toml", ex + "paper_cloth.toml", ex + "sweep_noise.toml"},
              [&](const std::string&, const std::string& mutated) {
                  return "run " + mutated + " --check -o " + run_dir + "/run";
              });
}

TEST(Fuzz, Dataset)
{
    const Corpus& k = corpus();
    fuzz_hdf5("dataset", {k.data}, [&](const std::string&, const std::string& m, const std::string& out) {
        static int turn = 0;
        switch (turn++ % 5) {
            case 0: return "info " + m;
            case 1: return "fit --method linear_pca " + m + " -o " + out;
            case 2: return "rollout " + m + " --method full_space --sequences all --frames 4 -o " + out;
            case 3: return "train-ae " + m + " -o " + out + " --latent 2 --epochs 2 --hidden 8 --pca 4";
            default: return "rollout " + m + " --integrator " + k.pca + " --sequences all -o " + out;
        }
    });
}

TEST(Fuzz, Autoencoder)
{
    const Corpus& k = corpus();
    fuzz_hdf5("autoencoder", {k.ae}, [&](const std::string&, const std::string& m, const std::string& out) {
        static int turn = 0;
        if (turn++ % 2 == 0) return "fit --method latent_mlp " + k.data + " --ae " + m + " -o " + out + " --set epochs=2";
        return "rollout " + k.data + " --integrator " + k.mlp + " --ae " + m + " --sequences all -o " + out;
    });
}

TEST(Fuzz, FittedMethod)
{
    const Corpus& k = corpus();
    fuzz_hdf5("artefact", {k.mlp, k.pca}, [&](const std::string& source, const std::string& m, const std::string& out) {
        const std::string ae = source == k.mlp ? " --ae " + k.ae : "";
        return "rollout " + k.data + " --integrator " + m + ae + " --sequences all -o " + out;
    });
}

TEST(Fuzz, Rollout)
{
    const Corpus& k = corpus();
    fuzz_hdf5("rollout", {k.rollout},
              [&](const std::string&, const std::string& m, const std::string&) { return "evaluate " + m; });
}

// Mutants of checkpoints whose fingerprint matches the command's options (item 7 of issue
// 44): most keep their fingerprint, so mutated weights, Adam moments and counters reach the
// loaders of both trainers, and some are resumed and trained on.
TEST(Fuzz, Checkpoint)
{
    const Corpus& k = corpus();
    const CheckpointCounts counts = fuzz_hdf5(
        "checkpoint", {k.ae_checkpoint, k.fit_checkpoint},
        [&](const std::string& source, const std::string& m, const std::string& out) {
            if (source == k.fit_checkpoint)
                return "fit --method latent_mlp " + k.data + " --ae " + k.ae + " -o " + out + kFitCheckpointOptions +
                       " --checkpoint " + m;
            return "train-ae " + k.data + " -o " + out + kAeCheckpointOptions + " --checkpoint " + m;
        },
        /*quiet=*/false);
    EXPECT_GE(counts.loader, counts.cases / 3) << counts.loader << " of " << counts.cases
                                              << " checkpoint mutants reached the loader";
    EXPECT_GE(counts.resumed, 1) << "no checkpoint mutant was resumed in " << counts.cases << " cases";
}

// The unmutated corpus checkpoints are resumed by the fuzz commands: the precondition of
// the campaign above (a fingerprint that did not match would set every mutant aside).
TEST(Fuzz, CheckpointCorpusIsResumed)
{
    const Corpus& k = corpus();
    ASSERT_TRUE(k.ok);
    const std::string dir = fresh_dir("fuzz_checkpoint_corpus");
    const std::string ae_copy = dir + "/ae_ck.h5", fit_copy = dir + "/fit_ck.h5";
    fs::copy_file(k.ae_checkpoint, ae_copy);
    fs::copy_file(k.fit_checkpoint, fit_copy);
    for (const std::string& args :
         {"train-ae " + k.data + " -o " + dir + "/ae.h5" + kAeCheckpointOptions + " --checkpoint " + ae_copy,
          "fit --method latent_mlp " + k.data + " --ae " + k.ae + " -o " + dir + "/mlp.h5" + kFitCheckpointOptions +
              " --checkpoint " + fit_copy}) {
        const auto r = testing::run_cli(args);
        EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
        EXPECT_NE(r.output.find("resuming from checkpoint"), std::string::npos) << args << "\n" << r.output;
        EXPECT_NE(r.output.find("at epoch 1"), std::string::npos) << args << "\n" << r.output;
    }
}

} // namespace
} // namespace lb
