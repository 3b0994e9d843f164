# The target fivebar_runtime (alias fivebar::runtime) and its install rules, shared by the whole
# project (lib/CMakeLists.txt) and the runtime's standalone project (lib/runtime/CMakeLists.txt,
# `cmake -S lib/runtime`: a C++17 compiler and nothing else). docs/runtime.md "Building and
# installing alone". Expects FIVEBAR_RUNTIME_LIB_DIR (the folder `lib`) and GNUInstallDirs.
set(FIVEBAR_RUNTIME_VERSION 0.1.0)
add_library(fivebar_runtime
  ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/controller.cpp
  ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/geometry.cpp
  ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/json_config.cpp
  ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/c_api.cpp
  ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/validate.cpp
)
add_library(fivebar::runtime ALIAS fivebar_runtime)
target_compile_features(fivebar_runtime PUBLIC cxx_std_17)
set_target_properties(fivebar_runtime PROPERTIES CXX_STANDARD 17 CXX_EXTENSIONS OFF POSITION_INDEPENDENT_CODE ON
                                                 EXPORT_NAME runtime VERSION ${FIVEBAR_RUNTIME_VERSION} SOVERSION 0)
target_include_directories(fivebar_runtime
  PUBLIC $<BUILD_INTERFACE:${FIVEBAR_RUNTIME_LIB_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
  PRIVATE ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime)
if(TARGET fivebar_warnings)
  target_link_libraries(fivebar_runtime PRIVATE $<BUILD_INTERFACE:fivebar_warnings>)
endif()
# Same rounding as the library: no FMA contraction, no errno from the maths.
target_compile_options(fivebar_runtime PRIVATE -fno-math-errno -ffp-contract=off)
# A C program links the static runtime with the C driver, which does not add the C++ standard
# library: the target brings it (and libm) itself, so a `project(... LANGUAGES C)` consumer links.
get_target_property(_fivebar_runtime_type fivebar_runtime TYPE)
if(_fivebar_runtime_type STREQUAL "STATIC_LIBRARY" AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  target_link_libraries(fivebar_runtime INTERFACE $<$<LINK_LANGUAGE:C>:stdc++> $<$<LINK_LANGUAGE:C>:m>)
endif()

# The Linux I/O backend (fivebar/runtime/linux_io.hpp: the kernel's IIO, PWM and GPIO sysfs files),
# device side: a library of its own beside the core, so the controller stays platform-free.
if(CMAKE_SYSTEM_NAME STREQUAL "Linux")
  add_library(fivebar_runtime_linux ${FIVEBAR_RUNTIME_LIB_DIR}/src/runtime/linux_io.cpp)
  add_library(fivebar::runtime_linux ALIAS fivebar_runtime_linux)
  target_compile_features(fivebar_runtime_linux PUBLIC cxx_std_17)
  set_target_properties(fivebar_runtime_linux PROPERTIES CXX_STANDARD 17 CXX_EXTENSIONS OFF POSITION_INDEPENDENT_CODE ON
                                                         EXPORT_NAME runtime_linux VERSION ${FIVEBAR_RUNTIME_VERSION} SOVERSION 0)
  target_include_directories(fivebar_runtime_linux
    PUBLIC $<BUILD_INTERFACE:${FIVEBAR_RUNTIME_LIB_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(TARGET fivebar_warnings)
    target_link_libraries(fivebar_runtime_linux PRIVATE $<BUILD_INTERFACE:fivebar_warnings>)
  endif()
  set(_fivebar_runtime_targets fivebar_runtime fivebar_runtime_linux)
else()
  set(_fivebar_runtime_targets fivebar_runtime)
endif()

# Components: `runtime` (the shared library, when built shared) and `development` (headers, the
# static library, the CMake package with its version file).
install(TARGETS ${_fivebar_runtime_targets} EXPORT fivebarRuntimeTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT development
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(DIRECTORY ${FIVEBAR_RUNTIME_LIB_DIR}/include/fivebar/runtime DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/fivebar
        COMPONENT development)
install(FILES ${FIVEBAR_RUNTIME_LIB_DIR}/include/fivebar/runtime.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/fivebar
        COMPONENT development)
# find_package(fivebar_runtime 0.1) then target_link_libraries(... fivebar::runtime): nothing else.
include(CMakePackageConfigHelpers)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/fivebar_runtimeConfigVersion.cmake
                                 VERSION ${FIVEBAR_RUNTIME_VERSION} COMPATIBILITY SameMinorVersion)
install(EXPORT fivebarRuntimeTargets NAMESPACE fivebar:: FILE fivebar_runtimeConfig.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/fivebar_runtime COMPONENT development)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/fivebar_runtimeConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/fivebar_runtime COMPONENT development)
