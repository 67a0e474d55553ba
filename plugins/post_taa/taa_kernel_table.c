/* post_taa kernels: this copy's table (taa_kernel.h), the one symbol the driver calls by
 * the instruction set's name. */
#include "taa_kernel.h"

#define TT__NET_STR2(x) #x
#define TT__NET_STR(x) TT__NET_STR2(x)

static const tt__net_kernels g_kernels = {
    .name = TT__NET_STR(TT__NET_ISA),
    .conv = TT__NET_K(conv),
    .mix = TT__NET_K(mix),
#if TT__NET_HAVE_AVX2
    .wino = TT__NET_K(wino),
    .wino4 = TT__NET_K(wino4),
#endif
    .input_rows = TT__NET_K(input_rows),
};

/* This instruction set's kernels (named after TT__NET_ISA). */
const tt__net_kernels *TT__NET_CAT(tt__net_kernels, _, TT__NET_ISA)(void) { return &g_kernels; }
