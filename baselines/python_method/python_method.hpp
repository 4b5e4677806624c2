#pragma once
// method = "python": a researcher's integrator written in Python, run by the harness like
// every C++ method (same dataset, autoencoder, rollouts, metrics, tables, work units and
// Slurm arrays). The class runs in a separate /usr/bin/python3 process (no shell), the
// host python/latentbench/plugin_host.py, over a pipe; docs/python.md, "Python
// integrators", states the class's interface and the protocol.
//
// Options: module, class (required), path (a directory put first on sys.path; relative to
// the suite file), python (the interpreter, default /usr/bin/python3), options (a table
// passed to the class's constructor as keyword arguments). The module's source hash enters
// options_text(), so editing the module refits it.
//
// Latent space: the harness encodes the two starting frames with the scene's autoencoder,
// the class steps the latent, and the harness decodes it (decode time is measured apart, as
// for the paper's integrator). A class that raises, returns a wrong shape or a non-finite
// latent from finite inputs is an Error naming the class, the call and the frame.
#include "methods/method.hpp"

namespace lb {

MethodFactory python_method();

} // namespace lb
