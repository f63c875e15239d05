# Debian's ParaView 5.11 CMake config does not find its own transitive dependencies; these calls
# must come first (see ../shared/notes/paraview-debian.md). A ParaView built elsewhere (EGL/OSMesa on
# a GPU cluster) is found the same way through ParaView_DIR.
set(_pv_vtk_modules /usr/lib/x86_64-linux-gnu/cmake/paraview-5.11/vtk)
if(EXISTS ${_pv_vtk_modules})
  list(APPEND CMAKE_MODULE_PATH ${_pv_vtk_modules})
endif()
find_package(MPI QUIET COMPONENTS C CXX)
find_package(Freetype QUIET)
find_package(X11 QUIET)
find_package(GLEW QUIET)
find_package(LibXml2 QUIET)
find_package(Boost QUIET)
find_package(NetCDF QUIET)
# VTK::hdf5 links hdf5::hdf5_hl, which the solver's HDF5 search (C only) does not define.
find_package(HDF5 QUIET COMPONENTS C HL)
find_package(ParaView 5.11 QUIET COMPONENTS Catalyst PythonCatalyst RemotingServerManager RemotingLive)
if(ParaView_FOUND)
  set(SPATE_WITH_CATALYST ON)
  message(STATUS "ParaView ${ParaView_VERSION} found: Catalyst adaptor enabled")
else()
  message(STATUS "ParaView not found: Catalyst adaptor disabled")
endif()
