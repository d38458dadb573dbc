#pragma once
/// @file MemoryUsage.h
/// Resident memory of this process, as the kernel counts it (/proc/self/status): budgets are
/// promises, and these are the figures that show they hold.

#include <cstdint>

namespace tetrapage {

/// The current resident set (VmRSS), in bytes; 0 where the kernel does not say.
std::uint64_t resident_bytes();

/// The peak resident set (VmHWM) since the start or the last reset_peak_resident(), in bytes.
std::uint64_t peak_resident_bytes();

/// Resets the peak to the current resident set (writes "5" to /proc/self/clear_refs), so that
/// one stage's peak can be measured. Returns false where the kernel refuses.
bool reset_peak_resident();

}  // namespace tetrapage
