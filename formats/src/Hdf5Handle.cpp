#include "Hdf5Handle.h"

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

}  // namespace tetrapage::detail
