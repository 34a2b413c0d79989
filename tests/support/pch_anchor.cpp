// The executable the tests' precompiled header is built with (tests/CMakeLists.txt); its
// main() is GoogleTest's, with no tests.
