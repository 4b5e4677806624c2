#pragma once
// Exceptions thrown at the boundaries (configuration, files, CLI). Internal
// invariants use assert; solver non-convergence is reported as data (see
// solver/newton.hpp), never thrown from inside the solver loop.
#include <stdexcept>
#include <string>

namespace lb {

/// Base of all latentbench errors; what() is a complete, user-facing message.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) { }
};

/// A configuration value is missing, unknown, malformed or out of range.
class ConfigError : public Error {
public:
    using Error::Error;
};

/// A file cannot be read or written, or its contents are malformed.
class IoError : public Error {
public:
    using Error::Error;
};

/// A numerical procedure failed irrecoverably (NaN state, failed solve).
class NumericalError : public Error {
public:
    using Error::Error;
};

} // namespace lb
