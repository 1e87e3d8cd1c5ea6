/* test_dir.h: the end of a test's temporary directory. Removed when the test passed (the rig and
 * capture tests leave gigabytes of video otherwise), kept and named for a failure's files, and
 * kept for every test with RIBBON_TEST_KEEP=1 in the environment. */
#ifndef RIBBON_TESTS_TEST_DIR_H
#define RIBBON_TESTS_TEST_DIR_H

/* dir (from mkdtemp) removed with everything in it when passed and not kept; else one line
 * "# kept DIR (what)" on stdout. */
void test_dir_done(const char *dir, int passed, const char *what);

#endif
