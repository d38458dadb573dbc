#pragma once
// Internal: RAII for HDF5 identifiers and the translation of HDF5's error stack into
// tetrapage exceptions. Nothing here appears in a public header.

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <utility>

namespace tetrapage::detail {

/// Every entry point that calls HDF5 calls this first (cheap after the first call on a
/// thread). Once per process, before HDF5's first use, it asks HDF5 not to terminate at exit
/// (see Hdf5Handle.cpp); once per thread, it turns off HDF5's automatic printing of its error
/// stack (HDF5's thread-safe build keeps one error stack per thread).
void enter_hdf5();

/// The innermost message of the calling thread's HDF5 error stack ("" when empty), then
/// clears the stack.
std::string take_hdf5_error();

/// What a file stores for one variable-length string: its claimed length and the global heap
/// object (collection address, index) that holds its bytes.
struct StoredVlenString {
  std::uint64_t length = 0;
  std::uint64_t heap_address = 0;
  std::uint32_t heap_index = 0;
};

/// The stored descriptor of a scalar variable-length string attribute, read without HDF5's
/// conversion (which allocates the claimed length, twice, before reading a byte of it): a
/// conversion to an opaque type of our own leaves the stored bytes as they are. `address_bytes`
/// is the file's size of addresses (H5Pget_sizes). False if HDF5 cannot read the attribute.
bool read_stored_vlen_string(hid_t attribute, std::size_t address_bytes, StoredVlenString& stored);

/// An owned HDF5 identifier closed by `Close` (H5Fclose, H5Dclose, ...).
template <herr_t (*Close)(hid_t)>
class Hdf5Handle {
 public:
  Hdf5Handle() = default;
  explicit Hdf5Handle(hid_t id) : id_(id) {}
  ~Hdf5Handle() { reset(); }
  Hdf5Handle(Hdf5Handle&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)) {}
  Hdf5Handle& operator=(Hdf5Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
    }
    return *this;
  }
  Hdf5Handle(const Hdf5Handle&) = delete;
  Hdf5Handle& operator=(const Hdf5Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  explicit operator bool() const { return valid(); }

  /// Closes now and reports whether HDF5 succeeded (destruction ignores the result).
  bool close() {
    if (!valid()) return true;
    const herr_t status = Close(std::exchange(id_, H5I_INVALID_HID));
    return status >= 0;
  }
  void reset() {
    if (valid()) Close(std::exchange(id_, H5I_INVALID_HID));
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
};

using FileHandle = Hdf5Handle<H5Fclose>;
using GroupHandle = Hdf5Handle<H5Gclose>;
using DatasetHandle = Hdf5Handle<H5Dclose>;
using DataspaceHandle = Hdf5Handle<H5Sclose>;
using DatatypeHandle = Hdf5Handle<H5Tclose>;
using AttributeHandle = Hdf5Handle<H5Aclose>;
using PropertyListHandle = Hdf5Handle<H5Pclose>;

}  // namespace tetrapage::detail
