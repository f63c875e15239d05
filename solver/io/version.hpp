#pragma once
// The program's version (CMake's project version) and the git commit it was built from
// (`<12 hex digits>[-dirty]`, or `unknown` outside git), baked in at build time by
// cmake/SpateVersion.cmake.
namespace spate {

const char* version();
const char* git_commit();

}  // namespace spate
