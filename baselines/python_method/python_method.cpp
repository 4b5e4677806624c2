#include "lb_paths.hpp"

#include "baselines/python_method/python_method.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/process.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "io/json.hpp"
#include "latent/autoencoder.hpp"
#include "sim/dataset.hpp"

namespace lb {

namespace {

namespace fs = std::filesystem;

constexpr const char* kArtefactGroup = "python";
constexpr std::uint64_t kMaxHeader = 1 << 24;
constexpr std::uint64_t kMaxArrayEntries = std::uint64_t(1) << 31;

struct Array {
    std::vector<hsize_t> dims;
    std::vector<double> data;
};
using Arrays = std::map<std::string, Array>;

Array vector_array(const VectorXd& v) { return {{hsize_t(v.size())}, std::vector<double>(v.data(), v.data() + v.size())}; }

/// A T × C matrix (rows are frames) as a C-order array.
Array rows_array(const MatrixXd& m)
{
    Array a{{hsize_t(m.rows()), hsize_t(m.cols())}, std::vector<double>(size_t(m.size()))};
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(a.data.data(), m.rows(), m.cols()) = m;
    return a;
}

std::string shape_text(const std::vector<hsize_t>& dims)
{
    std::string s = "(";
    for (size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
    return s + (dims.size() == 1 ? ",)" : ")");
}

/// Options of method = "python".
struct PythonOptions {
    std::string module;
    std::string class_name;
    std::string path;  ///< as written (stored in the artefact)
    std::string resolved_path;  ///< absolute, for sys.path ("" if none)
    std::string python = "/usr/bin/python3";
    toml::table options;  ///< the class's keyword arguments
    std::string module_hash;  ///< of the module's source file, set by resolve()
    std::uint64_t seed = 0;

    std::string label() const { return module + "." + class_name; }
};

std::string options_json(const toml::table& t)
{
    std::ostringstream s;
    s << toml::json_formatter{t, toml::format_flags::none};
    return s.str();
}

/// The Python host process of one class instance (python/latentbench/plugin_host.py): a
/// request is an 8-byte length, a JSON header and the raw float64 arrays it lists; a reply
/// the same with a TOML header (ok, error, arrays).
class PythonHost {
public:
    explicit PythonHost(const PythonOptions& o) : m_options(o), m_process(argv(o), environment())
    {
        toml::table reply = call("init",
                                 "\"module\": " + json_quote(o.module) + ", \"class\": " + json_quote(o.class_name) +
                                     ", \"path\": " + json_quote(o.resolved_path) +
                                     ", \"options\": " + options_json(o.options),
                                 {}, nullptr);
        m_module_file = reply["file"].value_or(std::string());
    }
    ~PythonHost() = default;

    const std::string& module_file() const { return m_module_file; }

    /// Send op with extra JSON fields and arrays; returns the reply header (arrays in *out).
    toml::table call(const std::string& op, const std::string& fields, const Arrays& arrays, Arrays* out,
                     const std::string& what_for_messages = "")
    {
        const std::string& what = what_for_messages.empty() ? op : what_for_messages;
        std::string header = "{\"op\": " + json_quote(op) + (fields.empty() ? "" : ", " + fields) + ", \"arrays\": [";
        bool first = true;
        for (const auto& [name, a] : arrays) {
            header += std::string(first ? "" : ", ") + "[" + json_quote(name) + ", [";
            for (size_t i = 0; i < a.dims.size(); ++i) header += (i ? ", " : "") + std::to_string(a.dims[i]);
            header += "]]";
            first = false;
        }
        header += "]}";
        const std::uint64_t n = header.size();
        bool sent = m_process.write_all(&n, sizeof n) && m_process.write_all(header.data(), header.size());
        for (const auto& [name, a] : arrays) {
            if (!sent) break;
            sent = m_process.write_all(a.data.data(), a.data.size() * sizeof(double));
        }
        if (!sent) exited(what);
        std::uint64_t reply_size = 0;
        if (!m_process.read_exact(&reply_size, sizeof reply_size)) exited(what);
        if (reply_size > kMaxHeader) fail(what, "sent a reply header of " + std::to_string(reply_size) + " bytes (protocol error)");
        std::string reply_text(reply_size, '\0');
        if (!m_process.read_exact(reply_text.data(), reply_text.size())) exited(what);
        toml::table reply;
        try {
            reply = parse_toml(reply_text, "reply of " + m_options.label());
        } catch (const Error& e) {
            fail(what, std::string("sent a malformed reply (protocol error): ") + e.what());
        }
        Arrays received;
        if (const toml::array* list = reply["arrays"].as_array()) {
            for (const toml::node& item : *list) {
                const toml::array* pair = item.as_array();
                const toml::array* dims = pair && pair->size() == 2 ? (*pair)[1].as_array() : nullptr;
                if (!dims || !(*pair)[0].is_string()) fail(what, "sent a malformed array list (protocol error)");
                Array a;
                std::uint64_t count = 1;
                for (const toml::node& d : *dims) {
                    const long long v = d.value_or(-1LL);
                    if (v < 0) fail(what, "sent a negative array extent (protocol error)");
                    a.dims.push_back(hsize_t(v));
                    count *= std::uint64_t(v);
                    if (count > kMaxArrayEntries) fail(what, "sent an array of more than 2^31 entries");
                }
                a.data.resize(size_t(count));
                if (!m_process.read_exact(a.data.data(), a.data.size() * sizeof(double))) exited(what);
                received[(*pair)[0].value_or(std::string())] = std::move(a);
            }
        }
        if (!reply["ok"].value_or(false)) fail(what, reply["error"].value_or(std::string("failed (no message)")));
        if (out) *out = std::move(received);
        return reply;
    }

    [[noreturn]] void fail(const std::string& op, const std::string& what) const
    {
        throw Error("python integrator '" + m_options.label() + "' (method = \"python\"): " + op + ": " + what);
    }

private:
    static std::vector<std::string> argv(const PythonOptions& o)
    {
        if (!fs::path(o.python).is_absolute())
            throw ConfigError("method python: key 'python' must be an absolute path to an interpreter (got '" +
                              o.python + "')");
        if (!fs::exists(o.python))
            throw ConfigError("method python: the interpreter '" + o.python +
                              "' does not exist (key 'python'; Debian's is /usr/bin/python3)");
        return {o.python, "-m", "latentbench.plugin_host"};
    }

    static std::vector<std::string> environment()
    {
        std::string path = std::string(LB_PYTHON_SOURCE_DIR) + ":" + LB_PYTHON_BUILD_DIR;
        if (const char* existing = std::getenv("PYTHONPATH"); existing && *existing) path += std::string(":") + existing;
        return {"PYTHONPATH=" + path, "PYTHONDONTWRITEBYTECODE=1", "PYTHONUNBUFFERED=1"};
    }

    [[noreturn]] void exited(const std::string& op)
    {
        const int status = m_process.finish(2.0);
        fail(op, "the Python process exited (status " + std::to_string(status) +
                     ") without replying; its error output is above (or in the unit's log)");
    }

    const PythonOptions& m_options;
    ChildProcess m_process;
    std::string m_module_file;
};

class PythonIntegrator final : public Integrator {
public:
    PythonIntegrator(std::string label, const PythonOptions& options, std::shared_ptr<Autoencoder> ae,
                     const Arrays& artefact)
        : m_label(std::move(label)), m_options(options), m_ae(std::move(ae)), m_host(m_options)
    {
        m_host.call("load", "\"latent_dim\": " + std::to_string(m_ae->latent_dim()), artefact, nullptr);
    }

    std::string name() const override { return m_label; }

    void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
               const BoundaryState& bc_prev) override
    {
        m_frame = 1;
        const Index d = m_ae->latent_dim();
        m_dead = !x_prev2.allFinite() || !x_prev.allFinite();
        if (m_dead) {
            m_latent = VectorXd::Constant(d, std::numeric_limits<double>::quiet_NaN());
            m_positions = VectorXd::Constant(x_prev.size(), std::numeric_limits<double>::quiet_NaN());
            return;
        }
        auto [z2, z1] = m_ae->encode_pair(x_prev2, x_prev);
        m_latent = z1;
        m_positions = x_prev;
        m_host.call("reset", "",
                    {{"z_prev2", vector_array(z2)}, {"z_prev", vector_array(z1)},
                     {"params_prev2", vector_array(bc_prev2.params)}, {"params_prev", vector_array(bc_prev.params)},
                     {"targets_prev2", vector_array(bc_prev2.targets)}, {"targets_prev", vector_array(bc_prev.targets)}},
                    nullptr, "reset (frames 0-1)");
    }

    StepTiming step(const BoundaryState& bc) override
    {
        ++m_frame;
        StepTiming timing;
        if (m_dead) return timing;  // a non-finite start stays non-finite (the stable horizon ends)
        Timer integrate;
        Arrays reply;
        const std::string op = "step (frame " + std::to_string(m_frame) + ")";
        m_host.call("step", "\"frame\": " + std::to_string(m_frame),
                    {{"params", vector_array(bc.params)}, {"targets", vector_array(bc.targets)}}, &reply, op);
        timing.integrate_seconds = integrate.seconds();
        const auto z = reply.find("z");
        const hsize_t d = hsize_t(m_ae->latent_dim());
        if (z == reply.end()) m_host.fail(op, "returned no latent");
        if (z->second.data.size() != d || z->second.dims.size() > 2)
            m_host.fail(op, "returned a latent of shape " + shape_text(z->second.dims) + "; the latent has " +
                                std::to_string(d) + " entries: return shape (" + std::to_string(d) + ",)");
        m_latent = Eigen::Map<const VectorXd>(z->second.data.data(), Index(d));
        if (!m_latent.allFinite())
            m_host.fail(op, "returned a non-finite latent from finite inputs (NaN or inf); a rollout that blows up "
                            "is detected from the decoded state, so return the finite latent the method computes");
        Timer decode;
        m_positions = m_ae->decode(m_latent, bc.targets);
        timing.decode_seconds = decode.seconds();
        return timing;
    }

    const VectorXd& positions() const override { return m_positions; }
    const VectorXd& latent() const override { return m_latent; }

private:
    std::string m_label;
    PythonOptions m_options;
    std::shared_ptr<Autoencoder> m_ae;
    PythonHost m_host;
    VectorXd m_latent, m_positions;
    Index m_frame = 0;
    bool m_dead = false;
};

class PythonMethod final : public Method {
public:
    explicit PythonMethod(PythonOptions options) : m_options(std::move(options)) { }

    std::string method_name() const override { return "python"; }
    bool needs_autoencoder() const override { return true; }
    bool failures_contained() const override { return true; }
    bool set_seed(std::uint64_t seed) override
    {
        m_options.seed = seed;
        return true;
    }

    /// Imports the class once (an ImportError or a missing class is reported here, before
    /// anything runs) and hashes its module's source file.
    void resolve(const MethodScene&) override
    {
        PythonHost host(m_options);
        const std::string& file = host.module_file();
        m_options.module_hash = file.empty() ? "none" : fnv1a64_hex(read_text_file(file));
    }

    std::string options_text() const override
    {
        toml::table t;
        t.insert_or_assign("module", m_options.module);
        t.insert_or_assign("class", m_options.class_name);
        if (!m_options.path.empty()) t.insert_or_assign("path", m_options.path);
        t.insert_or_assign("python", m_options.python);
        t.insert_or_assign("options", m_options.options);
        t.insert_or_assign("module_hash", m_options.module_hash);
        t.insert_or_assign("seed", (long long)m_options.seed);
        return to_toml_string(t);
    }

    std::string summary() const override { return "Python class " + m_options.label(); }

    void fit(const MethodInputs& in, h5::File& out) const override
    {
        PythonHost host(m_options);
        Arrays arrays;
        int k = 0;
        std::string names = "[";
        for (const SequenceData& q : in.data->sequences) {
            const Index t = q.train_frames;
            if (t < 3) continue;
            const std::string key = std::to_string(k++);
            arrays["latents." + key] = rows_array(in.autoencoder->encode(q.positions.topRows(t).transpose()).transpose());
            arrays["params." + key] = rows_array(q.bc_params.topRows(t));
            arrays["targets." + key] = rows_array(q.bc_positions.topRows(t));
            names += std::string(names.size() > 1 ? ", " : "") + json_quote(q.name);
        }
        names += "]";
        Arrays fitted;
        host.call("fit",
                  "\"seed\": " + std::to_string(m_options.seed) + ", \"sequences\": " + names +
                      ", \"dt\": " + std::to_string(in.data->physics.dt) +
                      ", \"dataset_path\": " + json_quote(in.dataset_path) +
                      ", \"autoencoder_path\": " + json_quote(in.autoencoder_path),
                  arrays, &fitted);
        for (const auto& [name, a] : fitted) {
            out.write_array(std::string(kArtefactGroup) + "/" + name, a.dims, a.data.data());
        }
        out.set_attribute("/", "python_arrays", (long long)fitted.size());
    }

    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        if (!artefact) throw Error("method python: no artefact to load");
        Arrays arrays;
        if (artefact->exists(kArtefactGroup)) {
            for (const std::string& name : artefact->list(kArtefactGroup)) {
                Array a;
                a.data = artefact->read_array(std::string(kArtefactGroup) + "/" + name, a.dims);
                arrays[name] = std::move(a);
            }
        }
        return std::make_unique<PythonIntegrator>(label, m_options, in.autoencoder, arrays);
    }

private:
    PythonOptions m_options;
};

bool valid_module_name(const std::string& s)
{
    if (s.empty() || s.front() == '.' || s.back() == '.') return false;
    for (char c : s) {
        if (!(std::isalnum((unsigned char)c) || c == '_' || c == '.')) return false;
    }
    return true;
}

std::unique_ptr<Method> parse_python(ConfigTable& entry, ConfigTable&)
{
    PythonOptions o;
    o.module = entry.require_string("module");
    o.class_name = entry.require_string("class");
    o.path = entry.get_string("path", "");
    o.python = entry.get_string("python", o.python);
    o.seed = std::uint64_t(entry.get_int("seed", 0, 0, std::numeric_limits<long long>::max()));
    entry.get_string("module_hash", "");  // stored in artefacts; resolve() recomputes it
    if (const toml::table* kwargs = entry.raw_table("options")) o.options = *kwargs;
    entry.accept("options");
    if (!valid_module_name(o.module)) entry.fail("module", "must be a dotted Python module name, e.g. \"linear_map\"");
    if (!valid_module_name(o.class_name) || o.class_name.find('.') != std::string::npos)
        entry.fail("class", "must be a Python class name, e.g. \"LinearLatentMap\"");
    if (!o.path.empty()) {
        fs::path p(o.path);
        // Relative to the suite file that names it (or the working directory from `fit --set`).
        if (p.is_relative()) {
            const fs::path source(entry.source());
            if (fs::exists(source) && fs::is_regular_file(source)) p = source.parent_path() / p;
        }
        std::error_code ec;
        const fs::path absolute = fs::absolute(p, ec).lexically_normal();
        if (ec || !fs::is_directory(absolute)) entry.fail("path", "'" + p.string() + "' is not a directory");
        o.resolved_path = absolute.string();
    }
    entry.finish();
    return std::make_unique<PythonMethod>(std::move(o));
}

} // namespace

MethodFactory python_method()
{
    MethodFactory f;
    f.name = "python";
    f.description = "a Python class (module, class) stepping the scene's latent in a /usr/bin/python3 process "
                    "(docs/python.md, \"Python integrators\")";
    f.parse = parse_python;
    f.quick_options = "module = \"linear_map\"\nclass = \"LinearLatentMap\"\npath = \"" LB_SOURCE_DIR
                      "/experiments/examples/python_integrator\"\n";
    return f;
}

} // namespace lb
