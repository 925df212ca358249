// The one error type of the library. Every failure bisect reports is an
// Error with a kind and, when it concerns a file, that file's name; the
// command line maps kinds to exit codes in one place (apps/bisect/main.cpp).
#pragma once

#include <stdexcept>
#include <string>

namespace bisect {

enum class ErrorKind {
  Input,    // a file or value the caller gave is invalid (exit 1)
  Usage,    // options that contradict each other or make no sense (exit 1)
  Check,    // an internal check failed: a bug, never the input's fault (exit 2)
  Limit,    // a limit the caller set would be passed (exit 3)
  Resource, // the system refused: disk full, permission, no memory (exit 1; 4 for memory)
};

struct Error : std::runtime_error {
  Error(ErrorKind kind, const std::string &file, const std::string &what)
      : std::runtime_error(file.empty() ? what : file + ": " + what), kind(kind), file(file) {}
  ErrorKind kind;
  std::string file; // the file the error concerns; empty when none
};

// Bad input: the message names the file and what is wrong.
struct InputError : Error {
  InputError(const std::string &file, const std::string &what)
      : Error(ErrorKind::Input, file, what) {}
};

// A file could not be written or read by the system (errno in words).
struct ResourceError : Error {
  ResourceError(const std::string &file, const std::string &what)
      : Error(ErrorKind::Resource, file, what) {}
};

// An internal invariant failed.
struct CheckError : Error {
  explicit CheckError(const std::string &what) : Error(ErrorKind::Check, {}, what) {}
};

// Contradictory or meaningless options.
struct UsageError : Error {
  explicit UsageError(const std::string &what) : Error(ErrorKind::Usage, {}, what) {}
};

} // namespace bisect
