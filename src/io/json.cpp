#include "io/json.hpp"

#include <cctype>
#include <cstdio>
#include <cmath>
#include <cstdlib>

#include "core/error.hpp"

namespace lb {

std::string json_quote(const std::string& text)
{
    std::string out = "\"";
    for (const unsigned char c : text) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += char(c);
        } else if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            out += buf;
        } else {
            out += char(c);
        }
    }
    return out + "\"";
}

const JsonValue& JsonValue::at(const std::string& key) const
{
    const auto it = obj.find(key);
    if (type != Type::object || it == obj.end()) throw IoError(what + ": missing key '" + key + "'");
    return it->second;
}

double JsonValue::number() const
{
    if (type != Type::number) throw IoError(what + ": expected a number");
    return num;
}

const std::string& JsonValue::string() const
{
    if (type != Type::string) throw IoError(what + ": expected a string");
    return str;
}

namespace {

class Parser {
public:
    Parser(const std::string& text, const std::string& what, int max_depth)
        : m_s(text), m_what(what), m_max_depth(max_depth)
    {
    }

    JsonValue document()
    {
        JsonValue v = value();
        skip_ws();
        if (m_pos != m_s.size()) error("trailing characters");
        return v;
    }

    [[noreturn]] void error(const std::string& what) const
    {
        throw IoError(m_what + ": malformed JSON (" + what + ") at offset " + std::to_string(m_pos));
    }

private:
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
                case 'r': c = '\r'; break;
                case 'b': c = '\b'; break;
                case 'f': c = '\f'; break;
                case '"': case '\\': case '/': c = e; break;
                case 'u': {
                    if (m_pos + 4 > m_s.size()) error("bad \\u escape");
                    const std::string hex = m_s.substr(m_pos, 4);
                    char* end = nullptr;
                    const long code = std::strtol(hex.c_str(), &end, 16);
                    if (end != hex.c_str() + 4 || code < 0 || code > 0x7f) error("unsupported \\u escape (ASCII only)");
                    m_pos += 4;
                    c = static_cast<char>(code);
                    break;
                }
                default: error("unsupported escape");
                }
            }
            out += c;
        }
        if (m_pos >= m_s.size()) error("unterminated string");
        ++m_pos;
        return out;
    }
    /// value() recurses once per '[' or '{': bounded so a hostile document cannot overflow the stack.
    struct DepthGuard {
        Parser& p;
        explicit DepthGuard(Parser& parser) : p(parser)
        {
            if (++p.m_depth > p.m_max_depth) p.error("nested deeper than " + std::to_string(p.m_max_depth) + " levels");
        }
        ~DepthGuard() { --p.m_depth; }
        DepthGuard(const DepthGuard&) = delete;
        DepthGuard& operator=(const DepthGuard&) = delete;
    };

    JsonValue value()
    {
        const DepthGuard guard(*this);
        skip_ws();
        if (m_pos >= m_s.size()) error("unexpected end");
        JsonValue v;
        v.what = m_what;
        const char c = m_s[m_pos];
        if (c == '{') {
            ++m_pos;
            v.type = JsonValue::Type::object;
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
            v.type = JsonValue::Type::array;
            if (consume(']')) return v;
            do v.arr.push_back(value());
            while (consume(','));
            expect(']');
        } else if (c == '"') {
            v.type = JsonValue::Type::string;
            v.str = string_body();
        } else if (literal("true")) {
            v.type = JsonValue::Type::boolean;
            v.b = true;
        } else if (literal("false")) {
            v.type = JsonValue::Type::boolean;
        } else if (literal("null")) {
            v.type = JsonValue::Type::null;
        } else {
            const char* begin = m_s.c_str() + m_pos;
            char* end = nullptr;
            v.type = JsonValue::Type::number;
            v.num = std::strtod(begin, &end);
            if (end == begin) error("unexpected character");
            // strtod also takes "nan", "inf" and overflows to inf; JSON has no such numbers.
            if (!std::isfinite(v.num)) error("non-finite number");
            m_pos += static_cast<std::size_t>(end - begin);
        }
        return v;
    }

    const std::string& m_s;
    const std::string m_what;
    const int m_max_depth;
    std::size_t m_pos = 0;
    int m_depth = 0;
};

} // namespace

JsonValue parse_json(const std::string& text, const std::string& what, std::size_t max_bytes, int max_depth)
{
    if (text.size() > max_bytes)
        throw IoError(what + ": description of " + std::to_string(text.size()) + " bytes exceeds the limit of " +
                      std::to_string(max_bytes));
    return Parser(text, what, max_depth).document();
}

} // namespace lb
