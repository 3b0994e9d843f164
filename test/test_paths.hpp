#pragma once
// Where the tests find the source tree and the built `fivebar`: read at run time from the build
// directory the test executable sits in (its CMakeCache.txt), not compiled in, so that a test's
// compiler command names no checkout path and a second checkout reuses the compiler cache.
// FIVEBAR_SOURCE_DIR and FIVEBAR_BINARY (test/CMakeLists.txt) expand to these calls.

namespace fivebar_test_paths {

/// The source tree (CMAKE_HOME_DIRECTORY of the build), e.g. "/work/fivebar".
const char* source_dir();
/// The built command-line program, `<build>/fivebar`.
const char* fivebar_binary();
/// The public data sets the tests read (the cache variable FIVEBAR_SHARED_DATA_DIR, test/CMakeLists.txt);
/// empty when the cache does not set it.
const char* shared_data_dir();

}  // namespace fivebar_test_paths
