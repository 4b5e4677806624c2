// Element energy + Hessian assembly (HessianAssembler::assemble) for the elastic
// energies on meshes of the scenes' sizes (DESIGN §5):
//   tets   40×8×8-cell beam: 3,321 vertices, 15,360 tets (≈ the 3,340-vertex armadillo)
//   shells 16×12 cloth grid: 192 vertices (the cloth scene)
//   rods   10×10 rods × 18 / × 36 vertices: 1,800 / 3,600 vertices (rods_translate / rods_rotate)
// Each benchmark runs with the element Hessians PSD-projected (as Newton does) and
// unprojected (arg 0), to separate the projection's cost from the kernels'. For TetStVK,
// whose projection clamps the analytic eigensystem of ∂P/∂F, the element benchmark also
// runs the generic 12×12 eigenvalue clamp (project_psd, arg 2) for reference.
// Counters: nnz of the assembled lower triangle, elements, and elements per second.
// value_gradient/<energy>: the training losses' hot loop instead (add_value_gradient, the
// serial pass vectorised across elements, energy/element_lanes.hpp), one thread.
#include <benchmark/benchmark.h>

#include <memory>

#include "core/rng.hpp"
#include "energy/hessian_assembler.hpp"
#include "energy/rod_bending.hpp"
#include "energy/rod_stretching.hpp"
#include "energy/shell_hinge_bending.hpp"
#include "energy/shell_membrane.hpp"
#include "energy/tet_stvk.hpp"
#include "mesh/generators.hpp"

namespace {

using namespace lb;

// A deformed state: rest + noise of `amplitude` (m) per coordinate, fixed seed.
VectorXd deformed_state(const Mesh& mesh, double amplitude)
{
    Rng rng(1);
    return flatten(mesh.rest_positions) + rng.uniform_vector(3 * mesh.num_vertices(), -amplitude, amplitude);
}

void run_assembly(benchmark::State& state, const Mesh& mesh, const EnergySum& energies, double amplitude)
{
    const bool project = state.range(0) != 0;
    const VectorXi all_free = VectorXi::LinSpaced(3 * mesh.num_vertices(), 0, int(3 * mesh.num_vertices() - 1));
    HessianAssembler assembler(all_free, energies);
    const VectorXd x = deformed_state(mesh, amplitude);
    Index elements = 0;
    for (const auto& term : energies.terms()) elements += term.energy->num_elements();
    for (auto _ : state) {
        assembler.assemble(energies, x, project);
        benchmark::DoNotOptimize(assembler.matrix().valuePtr());
        benchmark::ClobberMemory();
    }
    state.counters["nnz"] = double(assembler.matrix().nonZeros());
    state.counters["vertices"] = double(mesh.num_vertices());
    state.counters["elements"] = double(elements);
    state.counters["elements/s"] =
        benchmark::Counter(double(elements), benchmark::Counter::kIsIterationInvariantRate);
    state.SetLabel(project ? "psd-projected" : "unprojected");
}

/// A 40×8×8-cell tet beam (armadillo-sized) and its StVK energy.
const Mesh& armadillo_sized_beam()
{
    static const Mesh mesh = [] {
        TetBeamOptions options;
        options.nx = 40;
        options.ny = 8;
        options.nz = 8;
        options.size = Vector3d(1.0, 0.2, 0.2);
        return make_tet_beam(options);
    }();
    return mesh;
}
std::shared_ptr<TetStVK> beam_stvk()
{
    return std::make_shared<TetStVK>(armadillo_sized_beam().rest_positions, armadillo_sized_beam().elements, 1e7, 0.3);
}

void BM_TetStVK_Assemble(benchmark::State& state)
{
    EnergySum energies;
    energies.add(beam_stvk());
    run_assembly(state, armadillo_sized_beam(), energies, 0.005); // 20% of the 0.025 m cell
}
BENCHMARK(BM_TetStVK_Assemble)->Arg(1)->Arg(0)->ArgName("project")->Unit(benchmark::kMillisecond);

// The element kernel alone (no scatter), one thread: 0 unprojected, 1 projected as Newton
// does (analytic ∂P/∂F clamp), 2 the generic 12×12 eigenvalue clamp of the exact Hessian.
void BM_TetStVK_ElementHessian(benchmark::State& state)
{
    const std::shared_ptr<TetStVK> stvk = beam_stvk();
    const TetStVK& energy = *stvk;
    const VectorXd x = deformed_state(armadillo_sized_beam(), 0.005);
    const int mode = int(state.range(0));
    using ElementMatrix = TetStVK::ElementMatrix;
    ElementMatrix H;
    for (auto _ : state) {
        for (Index t = 0; t < energy.num_elements(); ++t) {
            energy.element_hessian(t, x, mode == 1, H.data());
            if (mode == 2) H = project_psd(H);
            benchmark::DoNotOptimize(H.data());
            benchmark::ClobberMemory();
        }
    }
    state.counters["elements/s"] =
        benchmark::Counter(double(energy.num_elements()), benchmark::Counter::kIsIterationInvariantRate);
    static const char* const kLabels[] = {"unprojected, 1 thread", "psd-projected (analytic dP/dF), 1 thread",
                                          "psd-projected (12x12 eigen-clamp), 1 thread"};
    state.SetLabel(kLabels[mode]);
}
BENCHMARK(BM_TetStVK_ElementHessian)->Arg(1)->Arg(0)->Arg(2)->ArgName("project")->Unit(benchmark::kMillisecond);

/// The cloth grid (16×12 vertices, 1 m × 0.75 m) and its two shell energies.
const Mesh& cloth_grid()
{
    static const Mesh mesh = make_cloth_grid(ClothGridOptions());
    return mesh;
}
std::shared_ptr<ShellMembrane> cloth_membrane()
{
    return std::make_shared<ShellMembrane>(cloth_grid().rest_positions, cloth_grid().elements, 1e5, 0.3, 1e-3);
}
std::shared_ptr<ShellHingeBending> cloth_hinges()
{
    return std::make_shared<ShellHingeBending>(cloth_grid().rest_positions, shell_hinge_stencils(cloth_grid().elements),
                                               1e5, 0.3, 1e-3);
}

void BM_Shell_Assemble(benchmark::State& state)
{
    EnergySum energies;
    energies.add(cloth_membrane());
    energies.add(cloth_hinges());
    run_assembly(state, cloth_grid(), energies, 0.01);
}
BENCHMARK(BM_Shell_Assemble)->Arg(1)->Arg(0)->ArgName("project")->Unit(benchmark::kMicrosecond);

void BM_Rods_Assemble(benchmark::State& state)
{
    RodBundleOptions options;
    options.num_rods_x = 10;
    options.num_rods_y = 10;
    options.vertices_per_rod = int(state.range(1));
    options.length = 0.5;
    options.spacing = 0.05;
    const Mesh mesh = make_rod_bundle(options);
    EnergySum energies;
    energies.add(std::make_shared<RodStretching>(mesh.rest_positions, mesh.elements, 1e7, 1e-3));
    energies.add(std::make_shared<RodBending>(mesh.rest_positions, rod_bending_stencils(mesh), 1e7, 1e-3));
    run_assembly(state, mesh, energies, 0.002);
}
BENCHMARK(BM_Rods_Assemble)
    ->Args({1, 18})
    ->Args({0, 18})
    ->Args({1, 36})
    ->Args({0, 36})
    ->ArgNames({"project", "vertices_per_rod"})
    ->Unit(benchmark::kMillisecond);

// add_value_gradient as the trainer calls it, once per sample inside its parallel batch
// loop: on one thread, the serial lane pass.
void run_value_gradient(benchmark::State& state, const Mesh& mesh, const Energy& energy, double amplitude)
{
    const VectorXd x = deformed_state(mesh, amplitude);
    VectorXd g = VectorXd::Zero(x.size());
    for (auto _ : state) {
        double value = 0.0;
#pragma omp parallel num_threads(1)
        value = energy.add_value_gradient(x, 1.0, g);
        benchmark::DoNotOptimize(value);
        benchmark::DoNotOptimize(g.data());
        benchmark::ClobberMemory();
    }
    state.counters["elements"] = double(energy.num_elements());
    state.counters["elements/s"] =
        benchmark::Counter(double(energy.num_elements()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ValueGradient_ShellHinge(benchmark::State& state)
{
    run_value_gradient(state, cloth_grid(), *cloth_hinges(), 0.01);
}
BENCHMARK(BM_ValueGradient_ShellHinge)->Name("value_gradient/shell_hinge")->Unit(benchmark::kMicrosecond);

void BM_ValueGradient_ShellMembrane(benchmark::State& state)
{
    run_value_gradient(state, cloth_grid(), *cloth_membrane(), 0.01);
}
BENCHMARK(BM_ValueGradient_ShellMembrane)->Name("value_gradient/shell_membrane")->Unit(benchmark::kMicrosecond);

void BM_ValueGradient_TetStVK(benchmark::State& state)
{
    run_value_gradient(state, armadillo_sized_beam(), *beam_stvk(), 0.005);
}
BENCHMARK(BM_ValueGradient_TetStVK)->Name("value_gradient/tet_stvk")->Unit(benchmark::kMicrosecond);

} // namespace

namespace {

// add_value_gradient_columns as the trainer calls it: Energy::kColumnLanes samples at once
// (here the same state in every lane; the arithmetic does not depend on it). The counter
// time/sample (seconds) sets it beside value_gradient/<energy>, whose time is one sample's.
void run_value_gradient_columns(benchmark::State& state, const Mesh& mesh, const Energy& energy, double amplitude)
{
    constexpr int W = Energy::kColumnLanes;
    const VectorXd x = deformed_state(mesh, amplitude);
    VectorXd X(x.size() * W), G = VectorXd::Zero(x.size() * W);
    for (Index r = 0; r < x.size(); ++r) X.segment<W>(r * W).setConstant(x[r]);
    for (auto _ : state) {
        double values[W] = {};
        energy.add_value_gradient_columns(X.data(), 1.0, G.data(), values);
        benchmark::DoNotOptimize(values);
        benchmark::DoNotOptimize(G.data());
        benchmark::ClobberMemory();
    }
    state.counters["elements"] = double(energy.num_elements());
    state.counters["time/sample"] =
        benchmark::Counter(W, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_ValueGradientColumns_ShellHinge(benchmark::State& state)
{
    run_value_gradient_columns(state, cloth_grid(), *cloth_hinges(), 0.01);
}
BENCHMARK(BM_ValueGradientColumns_ShellHinge)->Name("value_gradient_columns/shell_hinge")->Unit(benchmark::kMicrosecond);

void BM_ValueGradientColumns_ShellMembrane(benchmark::State& state)
{
    run_value_gradient_columns(state, cloth_grid(), *cloth_membrane(), 0.01);
}
BENCHMARK(BM_ValueGradientColumns_ShellMembrane)
    ->Name("value_gradient_columns/shell_membrane")
    ->Unit(benchmark::kMicrosecond);

void BM_ValueGradientColumns_TetStVK(benchmark::State& state)
{
    run_value_gradient_columns(state, armadillo_sized_beam(), *beam_stvk(), 0.005);
}
BENCHMARK(BM_ValueGradientColumns_TetStVK)->Name("value_gradient_columns/tet_stvk")->Unit(benchmark::kMicrosecond);

} // namespace
