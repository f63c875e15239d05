# Every dependency comes from Debian; optional ones are detected and reported, never required.
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Threads REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(fmt REQUIRED)
find_package(nlohmann_json REQUIRED)
# Case-file digests in summary.json (SHA-256) and snapshot compression (zlib).
find_package(OpenSSL REQUIRED COMPONENTS Crypto)
find_package(ZLIB REQUIRED)
find_package(spdlog REQUIRED)
# spate plot runs scripts/plot_probes.py (matplotlib) with this Python, and the tests their scripts
# (h5py, numpy). The Debian packages scripts/install-deps installs for them are importable by the
# system's interpreter only: a pyenv or venv python3 first on the PATH (as on the CI machines) lacks
# them, and with it the robustness tests were skipped and h5py-based checks failed. So the system's
# /usr/bin/python3 is preferred unless one is given (-DPython3_EXECUTABLE=...).
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python3 COMPONENTS Interpreter)
find_package(CLI11 CONFIG QUIET)
if(NOT CLI11_FOUND)
  # Debian's libcli11-dev ships only the header.
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
endif()

set(HDF5_PREFER_PARALLEL ON)
find_package(HDF5 REQUIRED COMPONENTS C)

option(SPATE_ENABLE_MPI "Build the MPI transport" ON)
set(SPATE_WITH_MPI OFF)
# Debian's HDF5 is the parallel (OpenMPI) flavour: its headers include mpi.h, so MPI's headers are
# needed even when the MPI transport is switched off.
if(SPATE_ENABLE_MPI OR HDF5_IS_PARALLEL)
  find_package(MPI COMPONENTS C CXX)
  if(MPI_FOUND AND SPATE_ENABLE_MPI)
    set(SPATE_WITH_MPI ON)
  endif()
endif()

include(CheckLanguage)
# nvcc on the PATH, in the system prefixes or in the toolkit's default place counts as found (CI
# shells often lack /usr/local/cuda/bin on the PATH; check_language alone looks only at the PATH).
if(NOT DEFINED CMAKE_CUDA_COMPILER AND "$ENV{CUDACXX}" STREQUAL "")
  find_program(SPATE_NVCC nvcc PATHS /usr/local/cuda/bin)
  if(SPATE_NVCC)
    set(CMAKE_CUDA_COMPILER "${SPATE_NVCC}" CACHE FILEPATH "CUDA compiler")
  endif()
endif()
check_language(CUDA)
set(_cuda_default OFF)
if(CMAKE_CUDA_COMPILER)
  set(_cuda_default ON)
endif()
option(SPATE_ENABLE_CUDA "Build the CUDA backend (on when nvcc is found)" ${_cuda_default})
option(SPATE_CUDA_AWARE_MPI "CUDA backend with MPI: hand device pointers to MPI (an MPI built with CUDA support) instead of staging halos through pinned host memory" OFF)
set(SPATE_WITH_CUDA OFF)
if(SPATE_ENABLE_CUDA)
  if(NOT DEFINED CMAKE_CUDA_ARCHITECTURES)
    set(CMAKE_CUDA_ARCHITECTURES 80 90)
  endif()
  enable_language(CUDA)
  find_package(CUDAToolkit REQUIRED)
  # CMake 3.25 (Debian 12) predates C++20 support for nvcc; nvcc >= 12 has -std=c++20.
  if(NOT CMAKE_CUDA20_STANDARD_COMPILE_OPTION AND CMAKE_CUDA_COMPILER_VERSION VERSION_GREATER_EQUAL 12.0)
    set(CMAKE_CUDA20_STANDARD_COMPILE_OPTION "-std=c++20")
    set(CMAKE_CUDA20_EXTENSION_COMPILE_OPTION "-std=c++20")
    set(CMAKE_CUDA20_COMPILE_FEATURES cuda_std_20)
    list(APPEND CMAKE_CUDA_COMPILE_FEATURES cuda_std_20)
  endif()
  set(SPATE_WITH_CUDA ON)
  message(STATUS "spate CUDA backend: nvcc ${CMAKE_CUDA_COMPILER_VERSION}, architectures ${CMAKE_CUDA_ARCHITECTURES}, CUDA-aware MPI ${SPATE_CUDA_AWARE_MPI}")
else()
  message(STATUS "spate CUDA backend: off (SPATE_ENABLE_CUDA=${SPATE_ENABLE_CUDA}; nvcc found: ${_cuda_default})")
endif()

option(SPATE_ENABLE_CATALYST "Build the ParaView Catalyst adaptor (on when ParaView is found)" ON)
set(SPATE_WITH_CATALYST OFF)
if(SPATE_ENABLE_CATALYST)
  include(cmake/SpateParaView.cmake)
endif()
include(cmake/SpateMesh.cmake)
include(cmake/SpateBodies.cmake)

if(SPATE_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
