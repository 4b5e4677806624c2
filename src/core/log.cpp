#include "core/log.hpp"

#include <cstdarg>
#include <cstdio>

namespace lb {
namespace {
LogLevel g_level = LogLevel::Info;
std::FILE* g_file = nullptr;

void vlog(const char* prefix, const char* format, va_list args)
{
    va_list copy;
    va_copy(copy, args);
    std::fprintf(stderr, "[latentbench]%s ", prefix);
    std::vfprintf(stderr, format, args);
    std::fputc('\n', stderr);
    std::fflush(stderr);
    if (g_file) {
        std::fprintf(g_file, "[latentbench]%s ", prefix);
        std::vfprintf(g_file, format, copy);
        std::fputc('\n', g_file);
        std::fflush(g_file);
    }
    va_end(copy);
}
} // namespace

void set_log_level(LogLevel level) { g_level = level; }

void set_log_file(const std::string& path)
{
    if (g_file) std::fclose(g_file);
    g_file = path.empty() ? nullptr : std::fopen(path.c_str(), "a");
}
LogLevel log_level() { return g_level; }

void log_info(const char* format, ...)
{
    if (g_level < LogLevel::Info) return;
    va_list args;
    va_start(args, format);
    vlog("", format, args);
    va_end(args);
}

void log_debug(const char* format, ...)
{
    if (g_level < LogLevel::Debug) return;
    va_list args;
    va_start(args, format);
    vlog(" debug:", format, args);
    va_end(args);
}

void log_warn(const char* format, ...)
{
    va_list args;
    va_start(args, format);
    vlog(" warning:", format, args);
    va_end(args);
}

Progress::Progress(std::string label, long total, double interval_seconds, long first)
    : m_label(std::move(label)), m_total(total), m_first(first), m_interval(interval_seconds),
      m_start(std::chrono::steady_clock::now()), m_last(m_start)
{
}

void Progress::update(long done, const std::string& extra)
{
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - m_last).count() < m_interval && done < m_total) {
        return;
    }
    m_last = now;
    const double elapsed = std::chrono::duration<double>(now - m_start).count();
    const double eta = done > m_first ? elapsed * double(m_total - done) / double(done - m_first) : 0.0;
    log_info("%s %ld/%ld  elapsed %.1fs  eta %.1fs  %s", m_label.c_str(), done, m_total, elapsed,
             eta, extra.c_str());
}

void Progress::finish(const std::string& extra)
{
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    log_info("%s done: %ld in %.2fs  %s", m_label.c_str(), m_total, elapsed, extra.c_str());
}

} // namespace lb
