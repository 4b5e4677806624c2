#include "io/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/log.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

constexpr const char* kTempTag = ".tmp-";

/// True unless `pid` is known not to run (kill(pid, 0) fails with ESRCH).
bool process_may_run(long pid)
{
    if (pid <= 0) return false;
    if (pid == long(::getpid())) return true;
    return ::kill(pid_t(pid), 0) == 0 || errno != ESRCH;
}

} // namespace

int remove_stale_temporaries(const std::string& path)
{
    const fs::path final_path(path);
    const fs::path dir = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
    const std::string prefix = final_path.filename().string() + kTempTag;
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    if (ec) return 0;  // no directory yet: nothing stale
    int removed = 0;
    for (const fs::directory_entry& entry : it) {
        const std::string name = entry.path().filename().string();
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string digits = name.substr(prefix.size());
        if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        const long pid = std::stol(digits);
        if (process_may_run(pid)) continue;
        if (fs::remove(entry.path(), ec)) {
            log_info("removed %s, left behind by process %ld, which no longer runs", entry.path().c_str(), pid);
            ++removed;
        }
    }
    return removed;
}

std::string output_path_problem(const std::string& path)
{
    std::error_code ec;
    const fs::path parent = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
    if (fs::is_directory(path, ec)) return "'" + path + "' is a directory";
    for (fs::path p = parent; !p.empty(); p = p.parent_path()) {  // the nearest existing ancestor
        if (fs::exists(p, ec)) {
            if (!fs::is_directory(p, ec)) return "'" + p.string() + "' is not a directory";
            break;
        }
        if (p == p.parent_path()) break;
    }
    if (!fs::exists(parent, ec)) return "directory '" + parent.string() + "' does not exist";
    if (::access(parent.c_str(), W_OK) != 0) return "directory '" + parent.string() + "' is not writable";
    return "";
}

void check_output_path(const std::string& path, const std::string& what)
{
    if (path.empty()) throw ConfigError(what + " is required");
    const std::string problem = output_path_problem(path);
    if (!problem.empty()) throw IoError(what + " '" + path + "': cannot write there: " + problem);
}

std::string create_failure_reason(const std::string& path)
{
    const int saved = errno;
    const std::string problem = output_path_problem(path);
    return problem.empty() ? std::string(std::strerror(saved)) : problem;
}

AtomicOutput::AtomicOutput(std::string final_path)
    : m_final(std::move(final_path)), m_temp(m_final + kTempTag + std::to_string(::getpid()))
{
    std::error_code ec;
    if (fs::is_directory(m_final, ec)) throw IoError("cannot write '" + m_final + "': it is a directory");
    remove_stale_temporaries(m_final);
}

AtomicOutput::~AtomicOutput()
{
    if (!m_committed) {
        std::error_code ec;
        fs::remove(m_temp, ec);
    }
}

void AtomicOutput::commit()
{
    std::error_code ec;
    fs::rename(m_temp, m_final, ec);
    if (ec) throw IoError("cannot move '" + m_temp + "' to '" + m_final + "': " + ec.message());
    m_committed = true;
}

void write_text_atomically(const std::string& path, const std::string& text)
{
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) {
        std::error_code ec;
        fs::create_directories(parent, ec);
        if (ec) throw IoError("cannot create '" + path + "': " + create_failure_reason(path));
    }
    AtomicOutput out(path);
    {
        std::ofstream file(out.temp_path(), std::ios::binary | std::ios::trunc);
        if (!file) throw IoError("cannot create '" + path + "': " + create_failure_reason(path));
        file << text;
        file.close();
        if (!file) throw IoError("cannot write '" + path + "' (disk full or I/O error)");
    }
    out.commit();
}

void copy_file_atomically(const std::string& from, const std::string& to)
{
    const fs::path parent = fs::path(to).parent_path();
    std::error_code ec;
    if (!parent.empty()) {
        fs::create_directories(parent, ec);
        if (ec) throw IoError("cannot create '" + to + "': " + create_failure_reason(to));
    }
    AtomicOutput out(to);
    fs::copy_file(from, out.temp_path(), fs::copy_options::overwrite_existing, ec);
    if (ec) throw IoError("cannot copy '" + from + "' to '" + to + "': " + ec.message());
    out.commit();
}

} // namespace lb
