#include "nn/architecture.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "nn/activation.hpp"
#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/residual_block.hpp"

namespace lb::nn {

namespace {

/// Layer widths above this are refused before anything is allocated (a corrupt
/// "in": 1e15 would otherwise end in std::bad_alloc).
constexpr Index kMaxWidth = Index(1) << 24;
/// Entries of one weight matrix (in × out), 2^31 (16 GiB of doubles).
constexpr Index kMaxWeights = Index(1) << 31;

// ---- a minimal JSON reader (objects, arrays, strings, numbers, true/false/null) ----
struct Json {
    enum class Type { null, boolean, number, string, array, object } type = Type::null;
    bool b = false;
    double num = 0.0;
    std::string str;
    std::vector<Json> arr;
    std::map<std::string, Json> obj;

    const Json& at(const std::string& key) const
    {
        auto it = obj.find(key);
        if (type != Type::object || it == obj.end())
            throw IoError("architecture: missing key '" + key + "'");
        return it->second;
    }
    bool has(const std::string& key) const { return type == Type::object && obj.count(key) > 0; }
    double number() const
    {
        if (type != Type::number) throw IoError("architecture: expected a number");
        return num;
    }
    /// A layer width: an integer in [0, kMaxWidth] (checked before the cast, which is
    /// undefined for values outside Index's range).
    Index index() const
    {
        const double v = number();
        if (!(v >= 0 && v <= double(kMaxWidth)) || v != std::floor(v))
            throw IoError("architecture: expected an integer width in [0, " + std::to_string(kMaxWidth) + "]");
        return static_cast<Index>(v);
    }
    const std::string& string() const
    {
        if (type != Type::string) throw IoError("architecture: expected a string");
        return str;
    }
};

class Parser {
public:
    explicit Parser(const std::string& text) : m_s(text) { }

    Json parse_document()
    {
        if (m_s.size() > kMaxArchitectureBytes)
            throw IoError("architecture: description of " + std::to_string(m_s.size()) + " bytes exceeds the limit of " +
                          std::to_string(kMaxArchitectureBytes));
        Json v = value();
        skip_ws();
        if (m_pos != m_s.size()) error("trailing characters");
        return v;
    }

private:
    [[noreturn]] void error(const std::string& what) const
    {
        throw IoError("architecture: malformed JSON (" + what + ") at offset " + std::to_string(m_pos));
    }
    void skip_ws()
    {
        while (m_pos < m_s.size() && std::isspace(static_cast<unsigned char>(m_s[m_pos]))) ++m_pos;
    }
    bool consume(char c)
    {
        skip_ws();
        if (m_pos < m_s.size() && m_s[m_pos] == c) {
            ++m_pos;
            return true;
        }
        return false;
    }
    void expect(char c)
    {
        if (!consume(c)) error(std::string("expected '") + c + "'");
    }
    bool literal(const char* word)
    {
        const std::string w(word);
        if (m_s.compare(m_pos, w.size(), w) == 0) {
            m_pos += w.size();
            return true;
        }
        return false;
    }
    std::string string_body()
    {
        expect('"');
        std::string out;
        while (m_pos < m_s.size() && m_s[m_pos] != '"') {
            char c = m_s[m_pos++];
            if (c == '\\') {
                if (m_pos >= m_s.size()) error("bad escape");
                const char e = m_s[m_pos++];
                switch (e) {
                case 'n': c = '\n'; break;
                case 't': c = '\t'; break;
                case '"': case '\\': case '/': c = e; break;
                default: error("unsupported escape");
                }
            }
            out += c;
        }
        if (m_pos >= m_s.size()) error("unterminated string");
        ++m_pos;
        return out;
    }
    /// Nesting depth of the value being parsed: value() recurses once per '[' or '{',
    /// so it is bounded to keep a hostile document from overflowing the stack.
    struct DepthGuard {
        Parser& p;
        explicit DepthGuard(Parser& parser) : p(parser)
        {
            if (++p.m_depth > kMaxArchitectureDepth)
                p.error("nested deeper than " + std::to_string(kMaxArchitectureDepth) + " levels");
        }
        ~DepthGuard() { --p.m_depth; }
        DepthGuard(const DepthGuard&) = delete;
        DepthGuard& operator=(const DepthGuard&) = delete;
    };

    Json value()
    {
        const DepthGuard guard(*this);
        skip_ws();
        if (m_pos >= m_s.size()) error("unexpected end");
        Json v;
        const char c = m_s[m_pos];
        if (c == '{') {
            ++m_pos;
            v.type = Json::Type::object;
            if (consume('}')) return v;
            do {
                skip_ws();
                std::string key = string_body();
                expect(':');
                v.obj[key] = value();
            } while (consume(','));
            expect('}');
        } else if (c == '[') {
            ++m_pos;
            v.type = Json::Type::array;
            if (consume(']')) return v;
            do v.arr.push_back(value());
            while (consume(','));
            expect(']');
        } else if (c == '"') {
            v.type = Json::Type::string;
            v.str = string_body();
        } else if (literal("true")) {
            v.type = Json::Type::boolean;
            v.b = true;
        } else if (literal("false")) {
            v.type = Json::Type::boolean;
        } else if (literal("null")) {
            v.type = Json::Type::null;
        } else {
            const char* begin = m_s.c_str() + m_pos;
            char* end = nullptr;
            v.type = Json::Type::number;
            v.num = std::strtod(begin, &end);
            if (end == begin) error("unexpected character");
            // strtod also takes "nan", "inf" and overflows to inf; JSON has no such numbers.
            if (!std::isfinite(v.num)) error("non-finite number");
            m_pos += static_cast<std::size_t>(end - begin);
        }
        return v;
    }

    const std::string& m_s;
    std::size_t m_pos = 0;
    int m_depth = 0;
};

Sequential build_sequential(const Json& j);

std::unique_ptr<Layer> build_layer(const Json& j)
{
    const std::string& type = j.at("type").string();
    if (type == "Sequential") return std::make_unique<Sequential>(build_sequential(j));
    if (type == "Linear") {
        const Index in = j.at("in").index(), out = j.at("out").index();
        if (in > 0 && out > kMaxWeights / in)
            throw IoError("architecture: Linear " + std::to_string(in) + " → " + std::to_string(out) + " is too large");
        return std::make_unique<Linear>(in, out);
    }
    if (type == "BatchNorm1d") {
        const double eps = j.has("eps") ? j.at("eps").number() : BatchNorm1d::default_eps;
        if (!(eps > 0)) throw IoError("architecture: BatchNorm1d eps must be positive");
        const double momentum = j.has("momentum") ? j.at("momentum").number() : BatchNorm1d::default_momentum;
        return std::make_unique<BatchNorm1d>(j.at("features").index(), eps, momentum);
    }
    if (type == "ResidualBlock") {
        std::optional<Linear> skip;
        const Json& s = j.at("skip");
        if (s.type != Json::Type::null) skip.emplace(s.at("in").index(), s.at("out").index());
        try {
            return std::make_unique<ResidualBlock>(build_sequential(j.at("f")), std::move(skip));
        } catch (const std::invalid_argument& e) {
            throw IoError(std::string("architecture: ") + e.what());
        }
    }
    try {
        const ActivationKind kind = activation_from_string(type);
        if (kind == ActivationKind::swish) return std::make_unique<Swish>();
        return std::make_unique<Activation>(kind);
    } catch (const ConfigError&) {
        throw IoError("architecture: unknown layer type '" + type + "'");
    }
}

Sequential build_sequential(const Json& j)
{
    if (j.at("type").string() != "Sequential") throw IoError("architecture: expected a Sequential");
    const Json& layers = j.at("layers");
    if (layers.type != Json::Type::array) throw IoError("architecture: 'layers' must be an array");
    Sequential net;
    for (const Json& l : layers.arr) {
        try {
            net.add(build_layer(l));
        } catch (const std::invalid_argument& e) {
            throw IoError(std::string("architecture: ") + e.what());
        }
    }
    return net;
}

} // namespace

std::string describe_architecture(const Sequential& net, bool has_standardizer)
{
    std::ostringstream os;
    os << std::setprecision(std::numeric_limits<double>::digits10);
    os << "{\"format\": \"" << architecture_format << "\", \"standardizer\": " << (has_standardizer ? "true" : "false")
       << ", \"network\": ";
    net.describe(os);
    os << "}";
    return os.str();
}

Architecture parse_architecture(const std::string& json)
{
    const Json doc = Parser(json).parse_document();
    const std::string& format = doc.at("format").string();
    if (format != architecture_format)
        throw IoError("architecture: unsupported format '" + format + "' (expected " + architecture_format + ")");
    Architecture a;
    a.network = build_sequential(doc.at("network"));
    const Json& s = doc.at("standardizer");
    if (s.type != Json::Type::boolean) throw IoError("architecture: 'standardizer' must be true or false");
    a.has_standardizer = s.b;
    return a;
}

} // namespace lb::nn
