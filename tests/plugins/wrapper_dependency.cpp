// The "CCD library" of wrapper_plugin.cpp, built twice: DEPENDENCY_ANSWER=1 finds every contact, 0 finds none. Both
// builds are named libbroken_dependency.so inside (their soname), as two builds of one library are.
extern "C" __attribute__((visibility("default"))) int ccdbench_test_dependency_answer() { return DEPENDENCY_ANSWER; }
