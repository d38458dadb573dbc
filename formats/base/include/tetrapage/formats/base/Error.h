#pragma once
/// @file Error.h
/// The one exception hierarchy of tetrapage. Every error that crosses a library boundary
/// derives from tetrapage::Error and names the file, the object and the value at fault.

#include <stdexcept>
#include <string>

namespace tetrapage {

/// Base of every tetrapage exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file could not be opened, read, written or renamed (the operating system said no).
class IoError : public Error {
 public:
  using Error::Error;
};

/// A file was readable but its contents are not what its format requires
/// (truncated, bad header, wrong version, checksum mismatch).
class FormatError : public Error {
 public:
  using Error::Error;
};

/// The content is well formed but unusable: NaN coordinates, indices out of range,
/// an empty mesh, an invalid argument or option value.
class InputError : public Error {
 public:
  using Error::Error;
};

}  // namespace tetrapage
