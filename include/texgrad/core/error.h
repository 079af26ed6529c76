// Typed exceptions thrown by every texgrad module; the CLI turns them into one line on stderr.
#pragma once

#include <stdexcept>
#include <string>

namespace texgrad {

/// Base class of all texgrad errors; what() is a complete, user-actionable sentence.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input (mesh, image, parameter) is malformed or inconsistent.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

/// A file could not be read or written.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A numerical step failed (factorisation not positive definite, NaN in a solve).
class NumericalError : public Error {
 public:
  using Error::Error;
};

/// The input is valid but uses a feature texgrad does not handle.
class UnsupportedError : public Error {
 public:
  using Error::Error;
};

}  // namespace texgrad
