#include "pipeline/stage_cache.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/atomic_file.hpp"
#include "io/hdf5.hpp"
#include "pipeline/experiment.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

std::string read_key(const std::string& file)
{
    std::ifstream in(file + ".key");
    std::string key;
    std::getline(in, key);
    return key;
}

void write_key(const std::string& file, const std::string& key) { write_text_atomically(file + ".key", key + "\n"); }

/// A cached HDF5 output must still open (a truncated or damaged file does not): a key
/// never stands for an unreadable file. Such a stage runs again.
bool readable(const std::string& file)
{
    if (fs::path(file).extension() != ".h5") return true;
    try {
        h5::File::open(file);
        return true;
    } catch (const Error& e) {
        log_warn("cached %s cannot be read (%s); running its stage again", file.c_str(), e.what());
        return false;
    }
}

} // namespace

StageCache::StageCache(std::set<std::string> forced) : m_forced(std::move(forced))
{
    const auto& stages = experiment_stages();
    for (const auto& f : m_forced) {
        if (f != "all" && std::find(stages.begin(), stages.end(), f) == stages.end()) {
            std::string known;
            for (const auto& s : stages) known += s + ", ";
            throw ConfigError("--force: unknown stage '" + f + "' (stages: " + known + "all)");
        }
    }
}

bool StageCache::forced(const std::string& stage) const { return m_forced.count(stage) || m_forced.count("all"); }

void StageCache::run(const std::string& stage, const std::string& what, const std::string& file,
                     const std::string& key, const std::function<void()>& work)
{
    if (!forced(stage) && fs::exists(file) && read_key(file) == key && readable(file)) {
        log_info("[%s] %s: cached (%s)", stage.c_str(), what.c_str(), file.c_str());
        ++m_cached;
        return;
    }
    log_info("[%s] %s ...", stage.c_str(), what.c_str());
    Timer t;
    fs::remove(file + ".key");
    work();
    write_key(file, key);
    log_info("[%s] %s: done in %.1f s", stage.c_str(), what.c_str(), t.seconds());
    ++m_ran;
}

} // namespace lb
