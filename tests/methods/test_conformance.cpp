// The contract every registered method must keep (src/methods/method.hpp), run over
// builtin_methods(): a method added with one registration line is tested here with
// no further code. On the small cantilever with a tiny autoencoder, each method is
// parsed from its quick options, fitted, loaded and rolled out, and must
//   - reject an unknown option key by name, and describe its resolved options as
//     TOML that parses back to the same text;
//   - keep the reset/step contract: 3N positions every frame, finite on the
//     training frames, a latent of fixed size;
//   - be deterministic: two fits with the same options give the same rollout;
//   - round-trip through its artefact: the method rebuilt from the file alone
//     (method name and options) gives the same rollout;
//   - end the stable horizon at a non-finite state instead of throwing.
#include <gtest/gtest.h>

#include <filesystem>

#include "baselines/builtin_methods.hpp"
#include "core/error.hpp"
#include "eval/rollout.hpp"
#include "io/hdf5.hpp"
#include "methods/artefact.hpp"
#include "scene/scene.hpp"
#include "../integrators/integrator_fixture.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;

struct Fitted {
    std::unique_ptr<Method> method;
    std::string artefact;  ///< "" if the method has none
};

class Conformance : public ::testing::TestWithParam<std::string> {
protected:
    static void SetUpTestSuite() { s_problem = std::make_unique<lb::testing::TinyProblem>("cantilever", 16, 3); }
    static void TearDownTestSuite() { s_problem.reset(); }

    const MethodFactory& factory() const { return builtin_methods().get(GetParam()); }

    MethodInputs inputs(const Method& m) const
    {
        MethodInputs in;
        in.data = &s_problem->data;
        in.model = s_problem->model.get();
        if (m.needs_autoencoder()) in.autoencoder = s_problem->ae;
        in.newton = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/cantilever.toml", {"small"}).newton;
        return in;
    }

    std::unique_ptr<Method> parsed(const std::string& extra = "") const
    {
        std::unique_ptr<Method> m = builtin_methods().parse_text(GetParam(), factory().quick_options + extra, "test");
        m->resolve({s_problem->data.scene_name, s_problem->ae->latent_dim()});
        return m;
    }

    Fitted fit(const std::string& file) const
    {
        Fitted f{parsed(), ""};
        if (f.method->has_artefact()) {
            f.artefact = std::string(LB_TEST_TMP_DIR) + "/conformance_" + GetParam() + "_" + file;
            fs::remove(f.artefact);
            fit_artefact(*f.method, inputs(*f.method), s_problem->data.scene_name, f.artefact, "test");
        }
        return f;
    }

    RolloutResult roll(const Method& m, const std::string& artefact, const SequenceData& seq, int frames) const
    {
        std::unique_ptr<h5::File> file;
        if (!artefact.empty()) file = std::make_unique<h5::File>(h5::File::open(artefact));
        const std::unique_ptr<Integrator> integrator = m.load(inputs(m), file.get(), GetParam());
        RolloutOptions ro;
        ro.max_frames = frames;
        return rollout(*integrator, *s_problem->model, seq, ro);
    }

    static std::unique_ptr<lb::testing::TinyProblem> s_problem;
};
std::unique_ptr<lb::testing::TinyProblem> Conformance::s_problem;

TEST_P(Conformance, OptionsRejectUnknownKeysAndRoundTrip)
{
    try {
        parsed("definitely_not_an_option = 1\n");
        FAIL() << GetParam() << " accepted an unknown key";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("definitely_not_an_option"), std::string::npos) << e.what();
    }
    const std::unique_ptr<Method> m = parsed();
    EXPECT_EQ(m->method_name(), GetParam());
    std::unique_ptr<Method> again = builtin_methods().parse_text(GetParam(), m->options_text(), "round trip");
    again->resolve({s_problem->data.scene_name, s_problem->ae->latent_dim()});
    EXPECT_EQ(again->options_text(), m->options_text());
    EXPECT_FALSE(m->summary().empty());
}

TEST_P(Conformance, ResetStepContract)
{
    const Fitted f = fit("contract.h5");
    const SequenceData& seq = s_problem->data.sequences.front();
    std::unique_ptr<h5::File> file;
    if (!f.artefact.empty()) file = std::make_unique<h5::File>(h5::File::open(f.artefact));
    const std::unique_ptr<Integrator> integrator = f.method->load(inputs(*f.method), file.get(), "label");
    ASSERT_TRUE(integrator);
    integrator->reset(seq.positions.row(0).transpose(), boundary_state(seq, 0), seq.positions.row(1).transpose(),
                      boundary_state(seq, 1));
    const Index latent = integrator->latent().size();
    for (Index t = 2; t < std::min<Index>(seq.train_frames, 8); ++t) {
        const StepTiming timing = integrator->step(boundary_state(seq, t));
        EXPECT_GE(timing.integrate_seconds, 0.0);
        EXPECT_GE(timing.decode_seconds, 0.0);
        ASSERT_EQ(integrator->positions().size(), s_problem->model->num_dofs()) << "frame " << t;
        EXPECT_TRUE(integrator->positions().allFinite()) << "frame " << t;
        EXPECT_EQ(integrator->latent().size(), latent) << "frame " << t;
    }
}

TEST_P(Conformance, DeterministicAndArtefactRoundTrip)
{
    const SequenceData& seq = s_problem->data.sequences.front();
    const Fitted a = fit("a.h5"), b = fit("b.h5");
    const RolloutResult ra = roll(*a.method, a.artefact, seq, 12);
    const RolloutResult rb = roll(*b.method, b.artefact, seq, 12);
    EXPECT_EQ(ra.positions, rb.positions) << "two fits with the same options and seed differ";
    if (a.artefact.empty()) return;
    // The method rebuilt from the artefact alone.
    const h5::File file = h5::File::open(a.artefact);
    std::unique_ptr<Method> rebuilt = method_from_artefact(builtin_methods(), file);
    EXPECT_EQ(rebuilt->method_name(), GetParam());
    rebuilt->resolve({s_problem->data.scene_name, s_problem->ae->latent_dim()});
    EXPECT_EQ(rebuilt->options_text(), a.method->options_text());
    const RolloutResult rc = roll(*rebuilt, a.artefact, seq, 12);
    EXPECT_EQ(ra.positions, rc.positions);
}

TEST_P(Conformance, NonFiniteStateEndsTheStableHorizon)
{
    const Fitted f = fit("nan.h5");
    SequenceData seq = s_problem->data.sequences.front();
    seq.positions.topRows(2).setConstant(std::numeric_limits<double>::quiet_NaN());
    RolloutResult r;
    ASSERT_NO_THROW(r = roll(*f.method, f.artefact, seq, 10));
    EXPECT_LE(r.summary.stable_horizon, 2);
}

std::vector<std::string> registered()
{
    std::vector<std::string> names;
    for (const MethodFactory& f : builtin_methods().all()) names.push_back(f.name);
    return names;
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, Conformance, ::testing::ValuesIn(registered()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

} // namespace
} // namespace lb
