# Mesh input (solids, fluid regions from STL/OBJ/PLY/VTP/VTK files; solver/case/mesh_shape.cpp)
# reads and queries meshes with VTK: ParaView's own VTK on Debian (the same libraries the Catalyst
# adaptor loads, so one process never holds two VTKs), else any VTK 9 found through VTK_DIR.
# Without it spate builds and runs; a case that names a mesh stops with a clear error.
option(SPATE_ENABLE_MESH "Read surface meshes with VTK (on when VTK is found)" ON)
set(SPATE_WITH_MESH OFF)
set(SPATE_MESH_VTK_COMPONENTS CommonCore CommonDataModel FiltersCore FiltersGeneral FiltersGeometry
    IOGeometry IOPLY IOXML IOLegacy)
if(SPATE_ENABLE_MESH)
  set(_pv_vtk_dir /usr/lib/x86_64-linux-gnu/cmake/paraview-5.11/vtk)
  if(EXISTS ${_pv_vtk_dir})
    list(APPEND CMAKE_MODULE_PATH ${_pv_vtk_dir})
    find_package(VTK CONFIG QUIET COMPONENTS ${SPATE_MESH_VTK_COMPONENTS} PATHS ${_pv_vtk_dir} NO_DEFAULT_PATH)
  endif()
  if(NOT VTK_FOUND)
    find_package(VTK 9 CONFIG QUIET COMPONENTS ${SPATE_MESH_VTK_COMPONENTS})
  endif()
  if(VTK_FOUND)
    set(SPATE_WITH_MESH ON)
    message(STATUS "VTK ${VTK_VERSION} found: mesh input enabled")
  else()
    message(STATUS "VTK not found: mesh input disabled (cases naming a mesh stop with an error)")
  endif()
endif()
