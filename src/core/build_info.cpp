#include "core/build_info.hpp"

#include <cstring>

namespace lb {

namespace {
std::vector<std::string>& recorded_command()
{
    static std::vector<std::string> argv;
    return argv;
}
} // namespace

std::string build_commit_short()
{
    const std::string full = build_commit();
    if (full == "unknown") return full;
    return full.substr(0, 12) + (build_dirty() ? "+dirty" : "");
}

void set_command_line(int argc, const char* const* argv)
{
    std::vector<std::string>& out = recorded_command();
    out.clear();
    for (int i = 0; i < argc; ++i) {
        std::string a = argv[i] ? argv[i] : "";
        if (i == 0) {
            const auto slash = a.find_last_of('/');
            if (slash != std::string::npos) a = a.substr(slash + 1);
        }
        out.push_back(std::move(a));
    }
}

const std::vector<std::string>& command_line() { return recorded_command(); }

std::string command_line_text()
{
    std::string text;
    for (const std::string& a : recorded_command()) {
        if (!text.empty()) text += ' ';
        if (a.empty() || a.find_first_of(" \t\"'\\") != std::string::npos) {
            text += '\'';
            for (char c : a) text += c == '\'' ? std::string("'\\''") : std::string(1, c);
            text += '\'';
        } else {
            text += a;
        }
    }
    return text;
}

} // namespace lb
