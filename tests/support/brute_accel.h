/* Test support: a brute-force tt_accel_iface (every triangle of every mesh, with a per-mesh
 * bounding-box cull) so path tests do not depend on Embree. Fine for scenes of a few
 * hundred triangles. */
#ifndef TT_TEST_BRUTE_ACCEL_H
#define TT_TEST_BRUTE_ACCEL_H

#include <tunetrace/accel.h>

/* The interface table (build ignores its config; counters are unsupported). */
const tt_accel_iface *tt_test_brute_accel(void);

#endif
