# Warnings on and clean; no errno from math functions (lets sqrtf inline and vectorise); floating-point contraction off so that every code path that computes a
# quantity rounds it the same way (bitwise determinism across splits and thread counts).
add_library(spate_options INTERFACE)
target_compile_options(spate_options INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wno-unknown-pragmas -ffp-contract=off -fno-math-errno -fno-trapping-math>)

# The instruction set and tuning of the CPU code (docs/performance.md, "Instruction set and
# tuning": chosen by measurement). SPATE_NATIVE=ON builds for this machine's instruction set with
# GCC's generic tuning: -march=native alone also takes the CPU's own tuning, and GCC's znver2
# tuning made a step about 10% slower than generic tuning of the same instructions; on the
# AVX-512 machine measured the two tunings are equally fast. A build for other machines sets
# SPATE_NATIVE=OFF (GCC's x86-64 baseline) or names its target, e.g.
# -DSPATE_ARCH_FLAGS="-march=x86-64-v3" for any CPU with AVX2. Results are bit-identical whatever
# the choice (-ffp-contract=off); only the speed differs. `spate bench --json` reports the flags.
if(SPATE_NATIVE)
  set(_spate_arch_default "-march=native -mtune=generic")
else()
  set(_spate_arch_default "")
endif()
# The default follows SPATE_NATIVE until a user sets the flags to something else.
if(NOT DEFINED SPATE_ARCH_FLAGS OR SPATE_ARCH_FLAGS STREQUAL "${_SPATE_ARCH_DEFAULT_USED}")
  set(SPATE_ARCH_FLAGS "${_spate_arch_default}" CACHE STRING "Instruction-set and tuning flags of the CPU code (default from SPATE_NATIVE)" FORCE)
endif()
set(_SPATE_ARCH_DEFAULT_USED "${_spate_arch_default}" CACHE INTERNAL "")
separate_arguments(_spate_arch_list UNIX_COMMAND "${SPATE_ARCH_FLAGS}")
target_compile_options(spate_options INTERFACE $<$<COMPILE_LANGUAGE:CXX>:${_spate_arch_list}>)
# What the build was made for, as `spate bench --json` reports it (with CMAKE_CXX_FLAGS, where a
# user may put -march too).
string(STRIP "${CMAKE_CXX_FLAGS} ${SPATE_ARCH_FLAGS}" _spate_arch_report)
target_compile_definitions(spate_options INTERFACE "$<$<COMPILE_LANGUAGE:CXX>:SPATE_ARCH_FLAGS=\"${_spate_arch_report}\">")
