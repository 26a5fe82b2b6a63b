# Finds Tessera's dependencies (all from Debian 12 packages) and repairs two packaging faults.
include_guard(GLOBAL)

find_package(embree 3.13 REQUIRED)
find_package(TBB REQUIRED)
find_package(glm REQUIRED)
find_package(TinyGLTF REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(ZLIB REQUIRED)
find_package(Threads REQUIRED)

# Debian's OpenImageIO 2.4 target lists /usr/include/opencv4 as an include directory although
# libopenimageio-dev does not depend on OpenCV; CMake then refuses to use the target ("non-existent
# path"). Drop include directories that do not exist instead of requiring OpenCV headers.
# (Its dependency Imath may print a notice about a missing Python binding library: harmless, we do
# not use PyImath.)
# (A function, so that tests/fuzz, which finds OpenImageIO in its own directory scope, repairs it too.)
function(tessera_drop_missing_include_dirs)
  foreach(_target IN LISTS ARGN)
    if(TARGET ${_target})
      get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
      if(_dirs)
        set(_kept "")
        foreach(_d IN LISTS _dirs)
          if(EXISTS "${_d}")
            list(APPEND _kept "${_d}")
          endif()
        endforeach()
        set_target_properties(${_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
      endif()
    endif()
  endforeach()
endfunction()
find_package(OpenImageIO REQUIRED)
tessera_drop_missing_include_dirs(OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)

# Debian installs OpenColorIO's CMake package directly in /usr/share/cmake, where find_package does
# not look by default (it expects a per-package subfolder), and its targets file computes the install
# prefix by walking four directories up from /usr/lib/<triplet>/cmake/OpenColorIO, which from
# /usr/share/cmake ends at "/" and yields the include directory "/include". Search there, then point
# the target at the directory that really holds OpenColorIO/OpenColorIO.h.
find_package(OpenColorIO 2.1 REQUIRED PATHS /usr/share/cmake)
find_path(TESSERA_OCIO_INCLUDE_DIR OpenColorIO/OpenColorIO.h REQUIRED)
set_target_properties(OpenColorIO::OpenColorIO PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${TESSERA_OCIO_INCLUDE_DIR}")
