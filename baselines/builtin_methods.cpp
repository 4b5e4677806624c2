#include "baselines/builtin_methods.hpp"

#include "baselines/fulton_cubature/fulton_method.hpp"
#include "baselines/linear_pca/linear_pca_method.hpp"
#include "baselines/python_method/python_method.hpp"
#include "baselines/tan_physics_mlp/tan_method.hpp"

namespace lb {

const MethodRegistry& builtin_methods()
{
    static const MethodRegistry registry = [] {
        MethodRegistry r;
        register_core_methods(r);
        r.add(linear_pca_method());  // one line per method
        r.add(fulton_cubature_method());
        r.add(fulton_full_method());
        r.add(tan_physics_mlp_method());
        r.add(python_method());
        return r;
    }();
    return registry;
}

} // namespace lb
