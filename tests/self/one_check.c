/* The counterpart of no_checks: one passing check is a pass. */
#include "tt_test.h"

int main(void) {
  CHECK(1 + 1 == 2);
  return tt_test_finish("one_check");
}
