#pragma once
// The smallest complete method, used by README "Adding an integrator" and tested in
// test_adding_a_method.cpp: constant-velocity extrapolation,
//   x_t = x_{t−1} + damping · (x_{t−1} − x_{t−2}),  Dirichlet vertices set to their targets,
// with one option (`damping`, default 1). It has nothing to fit, but writes an
// artefact anyway (its mean training speed) to show the fit/load round trip.
#include "methods/method.hpp"

namespace lb::example {

MethodFactory constant_velocity_method();

} // namespace lb::example
