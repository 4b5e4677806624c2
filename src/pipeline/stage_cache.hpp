#pragma once
// The stage cache of `latentbench run`: every output file has a sidecar
// `<file>.key` holding a hash of the configuration that produced it and of its
// inputs' keys. A stage is skipped when its file exists with a matching key and
// the stage is not forced (`--force STAGE` or `--force all`). The key is removed
// before the work starts and written after it succeeds, so a killed stage re-runs.
// Training stages also keep checkpoints: a forced stage passes resume = false, so
// it trains from scratch; an unforced re-run resumes only a checkpoint whose
// fingerprint matches (integrators/trainer.hpp, latent/autoencoder.hpp).
#include <functional>
#include <set>
#include <string>

namespace lb {

class StageCache {
public:
    /// @throws ConfigError for a forced stage name that does not exist
    explicit StageCache(std::set<std::string> forced);

    bool forced(const std::string& stage) const;
    /// Runs `work` unless `file` exists with key `key` and `stage` is not forced.
    void run(const std::string& stage, const std::string& what, const std::string& file, const std::string& key,
             const std::function<void()>& work);

    int ran() const { return m_ran; }
    int cached() const { return m_cached; }

private:
    std::set<std::string> m_forced;
    int m_ran = 0;
    int m_cached = 0;
};

} // namespace lb
