#include "methods/registry.hpp"

#include "core/error.hpp"

namespace lb {

void MethodRegistry::add(MethodFactory factory)
{
    if (factory.name.empty() || !factory.parse) throw Error("a method needs a name and a parser");
    if (find(factory.name)) throw Error("method '" + factory.name + "' is registered twice");
    m_factories.push_back(std::move(factory));
}

const MethodFactory* MethodRegistry::find(const std::string& name) const
{
    for (const MethodFactory& f : m_factories) {
        if (f.name == name) return &f;
    }
    return nullptr;
}

std::string MethodRegistry::names() const
{
    std::string s;
    for (const MethodFactory& f : m_factories) s += (s.empty() ? "" : ", ") + f.name;
    return s;
}

const MethodFactory& MethodRegistry::get(const std::string& name) const
{
    const MethodFactory* f = find(name);
    if (!f) throw ConfigError("unknown method '" + name + "' (known: " + names() + ")");
    return *f;
}

std::unique_ptr<Method> MethodRegistry::parse(ConfigTable& entry, ConfigTable& defaults) const
{
    const std::string method = entry.get_string("method", "latent_mlp");
    const MethodFactory* f = find(method);
    if (!f) entry.fail("method", "unknown method '" + method + "' (known: " + names() + ")");
    return f->parse(entry, defaults);
}

std::unique_ptr<Method> MethodRegistry::parse_text(const std::string& method, const std::string& options_toml,
                                                   const std::string& source) const
{
    const MethodFactory& f = get(method);
    const toml::table table = parse_toml(options_toml, source);
    ConfigTable entry(table, "", source);
    const toml::table empty;
    ConfigTable defaults(empty, "", source);
    return f.parse(entry, defaults);
}

} // namespace lb
