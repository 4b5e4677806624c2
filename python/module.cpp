// _latentbench: the compiled half of the Python module `latentbench` (python/latentbench/).
// Thin bindings over the library: files as NumPy arrays (views into the C++ objects, not
// copies, where Eigen allows), the physics and the autoencoder for prototypes, and the
// command line run in-process (the verbs: python/latentbench/__init__.py).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "baselines/builtin_methods.hpp"
#include "cli/app.hpp"
#include "core/build_info.hpp"
#include "core/error.hpp"
#include "eval/metrics.hpp"
#include "eval/rollout.hpp"
#include "eval/summary_schema.hpp"
#include "io/hdf5.hpp"
#include "io/table.hpp"
#include "latent/autoencoder.hpp"
#include "latent/latent_potential.hpp"
#include "methods/artefact.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/run_status.hpp"
#include "scene/scene.hpp"
#include "sim/dataset.hpp"
#include "sim/physics_model.hpp"

namespace py = pybind11;
using namespace lb;

namespace {

// ---- rollout files -------------------------------------------------------------------
// A rollout summary as a dict: the whole-rollout fields, and "train" / "test" dicts of the
// window fields (eval/summary_schema.hpp lists them once).
py::dict summary_dict(const RolloutSummary& s)
{
    py::dict d, train, test;
#define LB_PY_rollout(type, field) d[#field] = s.field;
#define LB_PY_window(type, field) train[#field] = s.train.field; test[#field] = s.test.field;
#define LB_PY_FIELD(scope, type, field, ...) LB_PY_##scope(type, field)
    LB_SUMMARY_METRICS(LB_PY_FIELD)
#undef LB_PY_FIELD
#undef LB_PY_window
#undef LB_PY_rollout
    d["train"] = train;
    d["test"] = test;
    return d;
}

RolloutSummary summary_from_dict(const py::dict& d)
{
    RolloutSummary s;
    const py::dict train = d["train"].cast<py::dict>(), test = d["test"].cast<py::dict>();
#define LB_PY_rollout(type, field) s.field = d[#field].cast<type>();
#define LB_PY_window(type, field) s.train.field = train[#field].cast<type>(); s.test.field = test[#field].cast<type>();
#define LB_PY_FIELD(scope, type, field, ...) LB_PY_##scope(type, field)
    LB_SUMMARY_METRICS(LB_PY_FIELD)
#undef LB_PY_FIELD
#undef LB_PY_window
#undef LB_PY_rollout
    return s;
}

/// Every rollout of a file written by save_rollouts, positions and metrics included.
std::vector<RolloutResult> load_rollouts(const std::string& path)
{
    std::vector<RolloutResult> out;
    const std::vector<RolloutRecord> records = load_rollout_summaries(path);  // checks the kind
    const h5::File f = h5::File::open(path);
    for (size_t k = 0; k < records.size(); ++k) {
        const std::string g = "rollouts/" + std::to_string(k);
        RolloutResult r;
        r.method = records[k].method;
        r.sequence = records[k].sequence;
        r.summary = records[k].summary;
        r.metrics = f.read_matrix(g + "/metrics");
        if (f.exists(g + "/positions")) {
            std::vector<hsize_t> dims;
            const std::vector<double> p = f.read_array(g + "/positions", dims);
            if (dims.size() != 3 || dims[2] != 3)
                throw IoError("'" + path + "': dataset " + g + "/positions is not T×N×3");
            r.positions = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                p.data(), Index(dims[0]), Index(3 * dims[1]));
        }
        out.push_back(std::move(r));
    }
    return out;
}

// ---- artefacts -------------------------------------------------------------------------
/// Every dataset under `group` into `arrays` (numbers as float64 arrays in their stored
/// shape, strings as str), named by their path from the root without the leading '/'.
void read_datasets(const h5::File& f, const std::string& group, py::dict& arrays)
{
    for (const std::string& name : f.list(group)) {
        const std::string path = group == "/" ? name : group + "/" + name;
        std::vector<std::string> members;
        bool is_group = true;
        try {
            members = f.list(path);
        } catch (const IoError&) {
            is_group = false;
        }
        if (is_group) {
            read_datasets(f, path, arrays);
            continue;
        }
        try {
            arrays[py::str(path)] = f.read_string(path);
            continue;
        } catch (const IoError&) {
            // not a string: a numeric array, or read_array's IoError says what is wrong with it
        }
        std::vector<hsize_t> dims;
        std::vector<double> data = f.read_array(path, dims);
        std::vector<py::ssize_t> shape(dims.begin(), dims.end());
        arrays[py::str(path)] = py::array_t<double>(shape, data.data());
    }
}

py::dict load_artefact(const std::string& path)
{
    const h5::File f = h5::File::open(path);
    const ArtefactInfo info = read_artefact_info(f);  // IoError naming the file if it is not one
    py::dict d, arrays;
    d["method"] = info.method;
    d["options"] = info.options;
    d["scene"] = info.scene;
    d["config"] = f.has_attribute("/", "config") ? f.attribute_string("/", "config") : std::string();
    read_datasets(f, "/", arrays);
    d["arrays"] = arrays;
    return d;
}

// ---- physics -------------------------------------------------------------------------
void check_size(Index got, Index expected, const char* what)
{
    if (got != expected)
        throw ConfigError(std::string(what) + ": expected " + std::to_string(expected) + " entries, got " +
                          std::to_string(got));
}

/// The incremental potential at x with history (x_prev, x_prev2) and, with a penalty,
/// the Dirichlet targets (3B, xyz interleaved in the order of bc_indices).
struct PotentialCall {
    const PhysicsModel& model;
    IncrementalPotential pot;
    PotentialCall(const PhysicsModel& m, const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2,
                  const std::optional<VectorXd>& bc_targets, double penalty_weight)
        : model(m), pot(m, penalty_weight)
    {
        if (!(penalty_weight >= 0.0)) throw ConfigError("penalty_weight: must be >= 0");
        check_size(x.size(), m.num_dofs(), "x");
        check_size(x_prev.size(), m.num_dofs(), "x_prev");
        check_size(x_prev2.size(), m.num_dofs(), "x_prev2");
        pot.set_previous(x_prev, x_prev2);
        if (penalty_weight > 0.0) {
            if (!bc_targets) throw ConfigError("bc_targets: required with a penalty_weight > 0");
            const Index B = Index(m.bc_indices().size());
            check_size(bc_targets->size(), 3 * B, "bc_targets");
            const MatrixX3d t = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
                bc_targets->data(), B, 3);
            pot.set_bc_targets(t);
        }
    }
};

/// A 3N-by-S input of the autoencoder: a 1-D array is one state (returned 1-D again).
MatrixXd columns_of(const py::array_t<double, py::array::forcecast>& a, const char* what, bool& one)
{
    one = a.ndim() == 1;
    if (a.ndim() != 1 && a.ndim() != 2)
        throw ConfigError(std::string(what) + ": expected a 1-D (one state) or 2-D (one column each) array");
    const Index rows = Index(a.shape(0)), cols = a.ndim() == 1 ? 1 : Index(a.shape(1));
    MatrixXd m(rows, cols);
    if (a.ndim() == 1) {
        const auto r = a.unchecked<1>();
        for (Index i = 0; i < rows; ++i) m(i, 0) = r(i);
    } else {
        const auto r = a.unchecked<2>();
        for (Index i = 0; i < rows; ++i)
            for (Index j = 0; j < cols; ++j) m(i, j) = r(i, j);
    }
    return m;
}

py::object as_output(const MatrixXd& m, bool one)
{
    if (one) return py::cast(VectorXd(m.col(0)));
    return py::cast(m);
}

void check_rows(const MatrixXd& m, Index rows, const char* what)
{
    if (m.rows() != rows)
        throw ConfigError(std::string(what) + ": expected " + std::to_string(rows) + " rows (entries per state), got " +
                          std::to_string(m.rows()));
}

} // namespace

PYBIND11_MODULE(_latentbench, m)
{
    m.doc() = "latentbench's compiled bindings (use the package `latentbench`)";
    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

    // ---- the command line ----
    m.def(
        "run_cli",
        [](const std::vector<std::string>& args) {
            // The provenance of what the verb writes names the command it ran, from Python.
            std::vector<const char*> argv{"python:latentbench"};
            for (const std::string& a : args) argv.push_back(a.c_str());
            set_command_line(int(argv.size()), argv.data());
            cli::CliOutcome outcome;
            {
                py::gil_scoped_release release;
                outcome = cli::run_command_line("latentbench", args);
            }
            std::fflush(stdout);
            return std::make_pair(outcome.status, outcome.error);
        },
        py::arg("args"), "Run `latentbench ARGS...` in-process: (exit status, error line or '')");
    m.def("subcommand_options", &cli::subcommand_options, py::arg("subcommand"));
    m.def(
        "run_status",
        [](const std::string& suite, const std::string& output) {
            const ExperimentConfig ex = load_experiment(suite, builtin_methods());
            const ExperimentPlan plan = plan_experiment(ex, resolve_run_dir(ex, output));
            py::list units;
            for (const UnitStatus& s : run_status(plan)) {
                py::dict d;
                d["id"] = s.unit->id;
                d["kind"] = unit_kind_name(s.unit->kind);
                d["state"] = unit_state_name(s.state);
                d["where"] = s.where;
                d["detail"] = s.detail;
                d["trainer"] = s.progress ? py::cast(s.progress->trainer) : py::none();
                d["epoch"] = s.progress ? py::cast(s.progress->epoch) : py::none();
                d["epochs"] = s.progress && s.progress->epochs > 0 ? py::cast(s.progress->epochs) : py::none();
                d["seconds"] = s.progress && s.progress->seconds >= 0 ? py::cast(s.progress->seconds) : py::none();
                units.append(d);
            }
            return units;
        },
        py::arg("suite"), py::arg("output") = "",
        "`latentbench status SUITE [-o OUTPUT]` as data: one dict per work unit");

    // ---- datasets ----
    py::class_<SequenceData>(m, "Sequence")
        .def_readonly("name", &SequenceData::name)
        .def_readonly("train_frames", &SequenceData::train_frames)
        .def_property_readonly("num_frames", &SequenceData::num_frames)
        .def_property_readonly(
            "positions", [](SequenceData& s) -> MatrixXd& { return s.positions; }, py::return_value_policy::reference_internal,
            "T × 3N positions (a view)")
        .def_property_readonly(
            "bc_positions", [](SequenceData& s) -> MatrixXd& { return s.bc_positions; },
            py::return_value_policy::reference_internal, "T × 3B Dirichlet targets (a view)")
        .def_property_readonly(
            "bc_params", [](SequenceData& s) -> MatrixXd& { return s.bc_params; }, py::return_value_policy::reference_internal)
        .def_property_readonly(
            "newton", [](SequenceData& s) -> MatrixXd& { return s.newton; }, py::return_value_policy::reference_internal,
            "T × 3: Newton iterations, residual, seconds")
        .def("__repr__", [](const SequenceData& s) {
            return "<latentbench.Sequence '" + s.name + "': " + std::to_string(s.num_frames()) + " frames, train " +
                   std::to_string(s.train_frames) + ">";
        });

    py::class_<Dataset>(m, "Dataset")
        .def_static(
            "load", [](const std::string& path) { return std::make_unique<Dataset>(load_dataset(path)); }, py::arg("path"))
        .def("save", [](const Dataset& d, const std::string& path) { save_dataset(d, path); }, py::arg("path"))
        .def_readonly("scene_name", &Dataset::scene_name)
        .def_readonly("variant", &Dataset::variant)
        .def_readonly("scene_toml", &Dataset::scene_toml)
        .def_property_readonly("kind", [](const Dataset& d) { return to_string(d.physics.mesh.kind); })
        .def_property_readonly("dt", [](const Dataset& d) { return d.physics.dt; })
        .def_property_readonly("gravity", [](const Dataset& d) { return Vector3d(d.physics.gravity); })
        .def_property_readonly("bc_indices", [](const Dataset& d) { return d.physics.bc_indices; })
        .def_property_readonly(
            "rest_positions", [](Dataset& d) -> MatrixX3d& { return d.physics.mesh.rest_positions; },
            py::return_value_policy::reference_internal, "N × 3 (a view)")
        .def_property_readonly(
            "elements", [](Dataset& d) -> MatrixXi& { return d.physics.mesh.elements; },
            py::return_value_policy::reference_internal)
        .def_property_readonly("sequences",
                               [](py::object self) {
                                   Dataset& d = self.cast<Dataset&>();
                                   py::list out;
                                   for (SequenceData& s : d.sequences)
                                       out.append(py::cast(&s, py::return_value_policy::reference_internal, self));
                                   return out;
                               })
        .def("__repr__", [](const Dataset& d) {
            return "<latentbench.Dataset scene '" + d.scene_name + "'" + (d.variant.empty() ? "" : " (" + d.variant + ")") +
                   ", " + std::to_string(d.physics.mesh.num_vertices()) + " vertices, " +
                   std::to_string(d.sequences.size()) + " sequences>";
        });

    // ---- physics ----
    py::class_<PhysicsModel>(m, "Physics")
        .def(py::init([](const Dataset& d) { return std::make_unique<PhysicsModel>(d.physics); }), py::arg("dataset"))
        .def_static(
            "from_scene",
            [](const std::string& path, const std::string& variant) {
                return std::make_unique<PhysicsModel>(physics_spec(load_scene(path, {variant})));
            },
            py::arg("path"), py::arg("variant") = "")
        .def_property_readonly("num_dofs", &PhysicsModel::num_dofs)
        .def_property_readonly("dt", &PhysicsModel::dt)
        .def_property_readonly("bc_indices", &PhysicsModel::bc_indices)
        .def_property_readonly("masses", &PhysicsModel::masses, py::return_value_policy::reference_internal)
        .def("rest_state", &PhysicsModel::rest_state)
        .def("elastic_energy", [](const PhysicsModel& p, const VectorXd& x) {
            check_size(x.size(), p.num_dofs(), "x");
            return p.elastic_energy(x);
        })
        .def(
            "potential",
            [](const PhysicsModel& p, const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2,
               std::optional<VectorXd> bc_targets, double penalty_weight) {
                const PotentialCall c(p, x, x_prev, x_prev2, bc_targets, penalty_weight);
                return c.pot.value(x);
            },
            py::arg("x"), py::arg("x_prev"), py::arg("x_prev2"), py::arg("bc_targets") = py::none(),
            py::arg("penalty_weight") = 0.0,
            "E(x) = 1/(2h²)(x − x̃)ᵀM(x − x̃) + E_elastic(x) − Σ m g·x [+ w Σ_B |x_i − x*_i|²], x̃ = 2 x_prev − x_prev2")
        .def(
            "potential_and_gradient",
            [](const PhysicsModel& p, const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2,
               std::optional<VectorXd> bc_targets, double penalty_weight) {
                const PotentialCall c(p, x, x_prev, x_prev2, bc_targets, penalty_weight);
                VectorXd g;
                const double e = c.pot.value_gradient(x, g);
                return std::make_pair(e, g);
            },
            py::arg("x"), py::arg("x_prev"), py::arg("x_prev2"), py::arg("bc_targets") = py::none(),
            py::arg("penalty_weight") = 0.0, "(E(x), ∇E(x)); arguments as potential()");

    // ---- autoencoders ----
    py::class_<Autoencoder>(m, "Autoencoder")
        .def_static(
            "load",
            [](const std::string& path, const PhysicsModel& physics) {
                return std::make_unique<Autoencoder>(Autoencoder::load(path, physics.spec()));
            },
            py::arg("path"), py::arg("physics"))
        .def(
            "save", [](Autoencoder& ae, const std::string& path) { ae.save(path); }, py::arg("path"))
        .def_property_readonly("latent_dim", &Autoencoder::latent_dim)
        .def_property_readonly("num_features", &Autoencoder::num_features)
        .def_property_readonly("scene_name", &Autoencoder::scene_name)
        .def("content_hash", &Autoencoder::content_hash)
        .def(
            "encode",
            [](Autoencoder& ae, const py::array_t<double, py::array::forcecast>& x) {
                bool one = false;
                const MatrixXd X = columns_of(x, "x", one);
                check_rows(X, ae.encoding().num_dofs(), "x");
                return as_output(ae.encode(X), one);
            },
            py::arg("x"), "3N positions (or 3N × S, one state per column) → latent (or latent × S)")
        .def(
            "decode",
            [](Autoencoder& ae, const py::array_t<double, py::array::forcecast>& z,
               const py::array_t<double, py::array::forcecast>& bc_targets) {
                bool one = false, one_b = false;
                const MatrixXd Z = columns_of(z, "z", one), B = columns_of(bc_targets, "bc_targets", one_b);
                check_rows(Z, ae.latent_dim(), "z");
                if (B.cols() != Z.cols()) throw ConfigError("bc_targets: one column per latent column expected");
                return as_output(ae.decode(Z, B), one);
            },
            py::arg("z"), py::arg("bc_targets"), "latent (× S) and 3B Dirichlet targets (× S) → 3N positions (× S)")
        .def(
            "vjp",
            [](Autoencoder& ae, const py::array_t<double, py::array::forcecast>& z,
               const py::array_t<double, py::array::forcecast>& grad_x,
               const py::array_t<double, py::array::forcecast>& bc_targets) {
                bool one = false, one_g = false, one_b = false;
                const MatrixXd Z = columns_of(z, "z", one), G = columns_of(grad_x, "grad_x", one_g),
                               B = columns_of(bc_targets, "bc_targets", one_b);
                check_rows(Z, ae.latent_dim(), "z");
                check_rows(G, ae.encoding().num_dofs(), "grad_x");
                if (B.cols() != Z.cols() || G.cols() != Z.cols())
                    throw ConfigError("grad_x, bc_targets: one column per latent column expected");
                return as_output(ae.decoder_vjp(Z, G, B), one);
            },
            py::arg("z"), py::arg("grad_x"), py::arg("bc_targets"),
            "J_D(z)ᵀ grad_x: the latent gradient of a loss of the decoded positions");

    py::class_<LatentPotential>(m, "LatentPotential")
        .def(py::init([](const PhysicsModel& physics, Autoencoder& ae, double penalty_weight, bool overwrite) {
                 if (!(penalty_weight > 0.0)) throw ConfigError("penalty_weight: must be positive");
                 return std::make_unique<LatentPotential>(physics, ae, penalty_weight, overwrite);
             }),
             py::arg("physics"), py::arg("autoencoder"), py::arg("penalty_weight") = 1e5,
             py::arg("overwrite_dirichlet") = false, py::keep_alive<1, 2>(), py::keep_alive<1, 3>())
        .def_property_readonly("penalty_weight", &LatentPotential::penalty_weight)
        .def(
            "value_and_gradient",
            [](LatentPotential& lp, const VectorXd& z, const VectorXd& bc_targets, const VectorXd& x_prev,
               const VectorXd& x_prev2) {
                const Index n = lp.model().num_dofs();
                check_size(z.size(), lp.autoencoder().latent_dim(), "z");
                check_size(bc_targets.size(), 3 * Index(lp.model().bc_indices().size()), "bc_targets");
                check_size(x_prev.size(), n, "x_prev");
                check_size(x_prev2.size(), n, "x_prev2");
                VectorXd g;
                const double e = lp.value_and_gradient(z, bc_targets, x_prev, x_prev2, g);
                return std::make_pair(e, g);
            },
            py::arg("z"), py::arg("bc_targets"), py::arg("x_prev"), py::arg("x_prev2"),
            "(E(D(z)), J_D(z)ᵀ ∇E(D(z)))");

    // ---- rollouts ----
    py::class_<RolloutResult>(m, "Rollout")
        .def(py::init([](std::string method, std::string sequence, MatrixXd metrics, py::dict summary,
                         std::optional<MatrixXd> positions) {
                 auto r = std::make_unique<RolloutResult>();
                 r->method = std::move(method);
                 r->sequence = std::move(sequence);
                 r->metrics = std::move(metrics);
                 r->summary = summary_from_dict(summary);
                 if (positions) r->positions = std::move(*positions);
                 return r;
             }),
             py::arg("method"), py::arg("sequence"), py::arg("metrics"), py::arg("summary"),
             py::arg("positions") = py::none())
        .def_readonly("method", &RolloutResult::method)
        .def_readonly("sequence", &RolloutResult::sequence)
        .def_property_readonly(
            "metrics", [](RolloutResult& r) -> MatrixXd& { return r.metrics; }, py::return_value_policy::reference_internal,
            "T × metric_columns() per-frame metrics (a view)")
        .def_property_readonly(
            "positions",
            [](py::object self) -> py::object {
                RolloutResult& r = self.cast<RolloutResult&>();
                if (r.positions.size() == 0) return py::none();
                return py::cast(r.positions, py::return_value_policy::reference_internal, self);
            },
            "T × 3N positions (a view), or None if not stored")
        .def_property_readonly("summary", [](const RolloutResult& r) { return summary_dict(r.summary); });
    m.def("metric_columns", &metric_column_names, "Names of a rollout's metric columns");
    m.def("load_rollouts", &load_rollouts, py::arg("path"));
    m.def(
        "save_rollouts",
        [](const std::vector<RolloutResult>& rollouts, const std::string& path, const std::string& config) {
            save_rollouts(rollouts, path, config);
        },
        py::arg("rollouts"), py::arg("path"), py::arg("config") = "");
    m.def("load_rollout_summaries", [](const std::string& path) {
        py::list out;
        for (const RolloutRecord& r : load_rollout_summaries(path)) {
            py::dict d;
            d["method"] = r.method;
            d["sequence"] = r.sequence;
            d["summary"] = summary_dict(r.summary);
            out.append(d);
        }
        return out;
    });

    // ---- artefacts ----
    m.def("load_artefact", &load_artefact, py::arg("path"),
          "dict: method, options (TOML), scene, config, arrays {dataset path: float64 array or str}");

    // ---- tables ----
    py::class_<TableCell>(m, "TableCell")
        .def(py::init<std::string>())
        .def(py::init<std::string, double>())
        .def_readwrite("text", &TableCell::text)
        .def_readwrite("value", &TableCell::value)
        .def("__repr__", [](const TableCell& c) { return "TableCell('" + c.text + "')"; });
    py::class_<Table>(m, "Table")
        .def(py::init<>())
        .def_readwrite("title", &Table::title)
        .def_readwrite("caption", &Table::caption)
        .def_readwrite("label", &Table::label)
        .def_readwrite("columns", &Table::columns)
        .def_readwrite("rows", &Table::rows)
        .def_readwrite("notes", &Table::notes)
        .def("add_row", &Table::add_row)
        .def("to_markdown", [](const Table& t) { return to_markdown(t); })
        .def("to_csv", [](const Table& t) { return to_csv(t); })
        .def("to_latex", [](const Table& t) { return to_latex(t); })
        .def("write_csv", [](const Table& t, const std::string& path) { write_csv(t, path); }, py::arg("path"))
        .def("write", [](const Table& t, const std::string& stem) { return write_table_files(t, stem); },
             py::arg("stem"), "STEM.md, .csv and .tex; returns the paths")
        .def(
            "values",
            [](const Table& t) {
                py::list rows;
                for (const auto& row : t.rows) {
                    py::list r;
                    for (const TableCell& c : row) r.append(c.value ? py::cast(*c.value) : py::cast(c.text));
                    rows.append(r);
                }
                return rows;
            },
            "The rows as lists of float (cells with a number) or str");
    m.def("read_table", &read_csv, py::arg("path"), "A table's CSV (as the suites and diagnose write it)");
}
