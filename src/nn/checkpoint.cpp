#include "nn/checkpoint.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <system_error>

#include "core/error.hpp"
#include "core/log.hpp"

namespace lb::nn {

namespace {

constexpr const char* kPartsKey = "fingerprint.parts";
/// Set-aside copies of one checkpoint kept before refusing to make another.
constexpr int kMaxSetAside = 1000;

std::vector<std::string> split(const std::string& text, char separator)
{
    std::vector<std::string> out;
    std::string item;
    std::istringstream in(text);
    while (std::getline(in, item, separator)) out.push_back(item);
    return out;
}

/// "key=value;key=value" texts: the keys whose values differ, as "key a → b".
std::string describe_difference(const std::string& saved, const std::string& current)
{
    auto entries = [](const std::string& text) {
        std::map<std::string, std::string> kv;
        for (const std::string& item : split(text, ';')) {
            const auto eq = item.find('=');
            if (eq != std::string::npos) kv[item.substr(0, eq)] = item.substr(eq + 1);
        }
        return kv;
    };
    const auto a = entries(saved), b = entries(current);
    std::string out;
    auto note = [&](const std::string& key, const std::string& x, const std::string& y) {
        out += (out.empty() ? "" : ", ") + key + " " + x + " → " + y;
    };
    for (const auto& [key, value] : a) {
        const auto it = b.find(key);
        if (it == b.end()) note(key, value, "(none)");
        else if (it->second != value) note(key, value, it->second);
    }
    for (const auto& [key, value] : b)
        if (a.find(key) == a.end()) note(key, "(none)", value);
    return out;
}

} // namespace

void write_fingerprint(h5::File& file, const Fingerprint& fingerprint)
{
    std::string names;
    for (const auto& [name, value] : fingerprint.parts) {
        names += (names.empty() ? "" : ",") + name;
        file.set_attribute("/", "fingerprint." + name, value);
    }
    file.set_attribute("/", kPartsKey, names);
}

std::string fingerprint_mismatch(const h5::File& file, const Fingerprint& expected)
{
    if (!file.has_attribute("/", kPartsKey)) return "it carries no fingerprint (made by an older version)";
    std::string names;
    for (const auto& part : expected.parts) names += (names.empty() ? "" : ",") + part.first;
    for (const auto& [name, value] : expected.parts) {
        const std::string key = "fingerprint." + name;
        if (!file.has_attribute("/", key)) return "it has no '" + name + "' fingerprint";
        const std::string saved = file.attribute_string("/", key);
        if (saved == value) continue;
        const std::string detail = describe_difference(saved, value);
        return "its " + name + " differ" + (name.back() == 's' ? "" : "s") +
               (detail.empty() ? " (content hash " + saved + " vs " + value + ")" : " (" + detail + ")");
    }
    if (file.attribute_string("/", kPartsKey) != names)
        return "its fingerprint has other parts (" + file.attribute_string("/", kPartsKey) + " vs " + names + ")";
    return {};
}

void require_shape(const std::string& what, const MatrixXd& loaded, Index rows, Index cols)
{
    if (loaded.rows() != rows || loaded.cols() != cols)
        throw CheckpointMismatch("'" + what + "' is " + std::to_string(loaded.rows()) + "×" +
                                 std::to_string(loaded.cols()) + " in the checkpoint, " + std::to_string(rows) + "×" +
                                 std::to_string(cols) + " here");
}

void copy_network_state(Sequential& dst, Sequential& src)
{
    auto dp = dst.parameters(), sp = src.parameters();
    auto db = dst.buffers(), sb = src.buffers();
    if (dp.size() != sp.size() || db.size() != sb.size())
        throw CheckpointMismatch("the network has " + std::to_string(sp.size()) + " parameters and " +
                                 std::to_string(sb.size()) + " buffers in the checkpoint, " +
                                 std::to_string(dp.size()) + " and " + std::to_string(db.size()) + " here");
    for (std::size_t i = 0; i < dp.size(); ++i) {
        if (dp[i].name != sp[i].name)
            throw CheckpointMismatch("parameter " + std::to_string(i) + " is '" + sp[i].name +
                                     "' in the checkpoint, '" + dp[i].name + "' here");
        require_shape(dp[i].name, sp[i].value, dp[i].value.rows(), dp[i].value.cols());
    }
    for (std::size_t i = 0; i < db.size(); ++i) {
        if (db[i].name != sb[i].name)
            throw CheckpointMismatch("buffer " + std::to_string(i) + " is '" + sb[i].name + "' in the checkpoint, '" +
                                     db[i].name + "' here");
        require_shape(db[i].name, sb[i].value, db[i].value.rows(), db[i].value.cols());
    }
    for (std::size_t i = 0; i < dp.size(); ++i) dp[i].value = sp[i].value;
    for (std::size_t i = 0; i < db.size(); ++i) db[i].value = sb[i].value;
}

std::string set_aside_checkpoint(const std::string& path, const std::string& reason)
{
    // link() never replaces an existing name (EEXIST), so two set-asides, or two processes
    // setting aside at once, cannot destroy an earlier one; unlink() then frees the name.
    std::error_code ec;
    for (int n = 1; n <= kMaxSetAside; ++n) {
        const std::string stale = path + ".stale." + std::to_string(n);
        int error = 0;
        if (::link(path.c_str(), stale.c_str()) == 0) {
            if (::unlink(path.c_str()) != 0) {
                error = errno;
                ::unlink(stale.c_str());  // the checkpoint itself is still there: undo the copy
                throw IoError("checkpoint '" + path + "' cannot be resumed (" + reason +
                              ") and cannot be set aside: removing its name failed: " + std::strerror(error) +
                              "; move it away or choose another checkpoint path");
            }
        } else if ((error = errno) == EEXIST) {
            continue;
        } else if (std::filesystem::exists(stale, ec)) {
            continue;
        } else {
            // No hard links on this file system: a rename, after checking the name is free.
            std::filesystem::rename(path, stale, ec);
            if (ec)
                throw IoError("checkpoint '" + path + "' cannot be resumed (" + reason + ") and cannot be set aside as '" +
                              stale + "': " + ec.message() + "; it is left in place: move it away or choose another " +
                              "checkpoint path");
        }
        log_warn("checkpoint %s not resumed: %s; set aside as %s, training from scratch", path.c_str(), reason.c_str(),
                 stale.c_str());
        return stale;
    }
    throw IoError("checkpoint '" + path + "' cannot be resumed (" + reason + ") and " + std::to_string(kMaxSetAside) +
                  " set-aside copies '" + path + ".stale.N' exist already; remove some, or choose another checkpoint path");
}

void hash_network(Fnv1a64& hash, Sequential& net)
{
    for (const auto& p : net.parameters()) hash.add(p.name).add(p.value);
    for (const auto& b : net.buffers()) hash.add(b.name).add(b.value);
}

std::string exact_text(double value)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%a", value);
    return buf;
}

} // namespace lb::nn
