# Warnings on and clean; no errno from math functions (lets sqrtf inline and vectorise); floating-point contraction off so that every code path that computes a
# quantity rounds it the same way (bitwise determinism across splits and thread counts).
add_library(spate_options INTERFACE)
target_compile_options(spate_options INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wno-unknown-pragmas -ffp-contract=off -fno-math-errno -fno-trapping-math>)
if(SPATE_NATIVE)
  target_compile_options(spate_options INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-march=native>)
endif()
