#pragma once
// Whether a test may hold resident memory to a bound. Under AddressSanitizer it may not: its
// shadow memory and the quarantine of freed blocks add hundreds of MiB that are not the
// program's (make sanitize checks leaks there instead, with LeakSanitizer).

namespace tetrapage::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kResidentMemoryIsTheProgramsOwn = false;
#else
inline constexpr bool kResidentMemoryIsTheProgramsOwn = true;
#endif

}  // namespace tetrapage::test
