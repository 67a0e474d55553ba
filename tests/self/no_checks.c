/* A test that asserts nothing: tt_test_finish must fail it (meson: should_fail). */
#include "tt_test.h"

int main(void) { return tt_test_finish("no_checks"); }
