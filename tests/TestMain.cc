/// @file TestMain.cc
/// @brief GoogleTest main: initialises OpenVDB and, in Debug builds, traps floating-point
///        exceptions (invalid operation, division by zero) so that a NaN is caught where it is
///        made.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cfenv>

int
main(int argc, char** argv)
{
    openvdb::initialize();
#if !defined(NDEBUG) && defined(__GLIBC__)
    feenableexcept(FE_INVALID | FE_DIVBYZERO);
#endif
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
