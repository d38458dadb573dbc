#include "Hdf5Handle.h"

#include <array>
#include <cstring>

namespace tetrapage::detail {

void enter_hdf5() {
  // Before HDF5's first use in the process (when it is ours): no termination at exit. A file
  // whose close failed (a full disk while flushing an abandoned index) stays half closed in
  // HDF5, and its termination handler then crashes the process at exit (HDF5 1.10 closes the
  // broken file again). Every file is closed by its handle anyway.
  static const bool no_termination_at_exit = [] {
    H5dont_atexit();
    return true;
  }();
  (void)no_termination_at_exit;
  thread_local bool silenced = false;
  if (silenced) return;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  silenced = true;
}

namespace {

herr_t keep_innermost(unsigned depth, const H5E_error2_t* error, void* client) {
  if (depth != 0) return 0;
  auto& text = *static_cast<std::string*>(client);
  const std::string description = error->desc != nullptr ? error->desc : "";
  char minor[256] = {};
  const bool has_minor = H5Eget_msg(error->min_num, nullptr, minor, sizeof minor) > 0;
  if (!description.empty() && has_minor)
    text = description + " (" + minor + ")";
  else
    text = has_minor ? std::string(minor) : description;
  return 0;
}

}  // namespace

std::string take_hdf5_error() {
  std::string text;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keep_innermost, &text);
  H5Eclear2(H5E_DEFAULT);
  return text.empty() ? std::string("HDF5 gave no reason") : text;
}

namespace {

constexpr const char* kRawVlenTag = "tetrapage stored vlen string";
// A stored variable-length element is a 4-byte length, an address and a 4-byte heap index.
constexpr std::size_t kRawVlenBytes = 32;

/// A soft conversion from a variable-length string to our tagged opaque type that converts
/// nothing: the stored bytes stay in the buffer HDF5 then copies out.
herr_t keep_stored_bytes(hid_t source, hid_t target, H5T_cdata_t* data, std::size_t, std::size_t,
                         std::size_t, void*, void*, hid_t) {
  if (data->command != H5T_CONV_INIT) return 0;  // H5T_CONV_CONV: the bytes are the result
  if (H5Tget_class(target) != H5T_OPAQUE || H5Tis_variable_str(source) <= 0 ||
      H5Tget_size(target) < H5Tget_size(source))
    return -1;
  char* tag = H5Tget_tag(target);
  const bool ours = tag != nullptr && std::strcmp(tag, kRawVlenTag) == 0;
  H5free_memory(tag);
  if (!ours) return -1;
  data->need_bkg = H5T_BKG_NO;
  return 0;
}

std::uint64_t load_le(const unsigned char* bytes, std::size_t count) {
  std::uint64_t value = 0;
  for (std::size_t i = count; i-- > 0;) value = (value << 8) | bytes[i];
  return value;
}

}  // namespace

bool read_stored_vlen_string(hid_t attribute, std::size_t address_bytes, StoredVlenString& stored) {
  static const hid_t raw_type = [] {
    DatatypeHandle source(H5Tcopy(H5T_C_S1));
    H5Tset_size(source.get(), H5T_VARIABLE);
    const hid_t raw = H5Tcreate(H5T_OPAQUE, kRawVlenBytes);
    H5Tset_tag(raw, kRawVlenTag);
    H5Tregister(H5T_PERS_SOFT, "tetrapage: stored vlen string", source.get(), raw, keep_stored_bytes);
    return raw;  // kept for the process's life, as the registration is
  }();
  if (raw_type < 0 || address_bytes == 0 || 8 + address_bytes > kRawVlenBytes) return false;
  std::array<unsigned char, kRawVlenBytes> bytes{};
  if (H5Aread(attribute, raw_type, bytes.data()) < 0) return false;
  stored.length = load_le(bytes.data(), 4);
  stored.heap_address = load_le(bytes.data() + 4, address_bytes);
  stored.heap_index = static_cast<std::uint32_t>(load_le(bytes.data() + 4 + address_bytes, 4));
  return true;
}

}  // namespace tetrapage::detail
