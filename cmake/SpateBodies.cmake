# Bodies the water moves (issue 32; solver/sim/rigid_bodies.*): their rigid-body dynamics, joints
# and constraints come from Simbody (Debian's libsimbody-dev; docs/design.md says why Simbody).
# Without it spate builds and runs; a case with a floating solid stops with a clear error.
option(SPATE_ENABLE_BODIES "Floating solids through Simbody (on when Simbody is found)" ON)
set(SPATE_WITH_BODIES OFF)
if(SPATE_ENABLE_BODIES)
  find_package(Simbody CONFIG QUIET)
  if(Simbody_FOUND)
    set(SPATE_WITH_BODIES ON)
    message(STATUS "Simbody ${Simbody_VERSION} found: floating solids enabled")
  else()
    message(STATUS "Simbody not found: floating solids disabled (cases with one stop with an error)")
  endif()
endif()
