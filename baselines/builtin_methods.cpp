#include "baselines/builtin_methods.hpp"

#include "baselines/linear_pca/linear_pca_method.hpp"

namespace lb {

const MethodRegistry& builtin_methods()
{
    static const MethodRegistry registry = [] {
        MethodRegistry r;
        register_core_methods(r);
        r.add(linear_pca_method());  // one line per method
        return r;
    }();
    return registry;
}

} // namespace lb
