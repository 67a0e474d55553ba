/* host: sequence rendering for temporal filters (--sequence): a scene's camera path frame by
 * frame with the Halton(2,3) jitter cycle of 8, per-frame colour/depth/motion EXRs and a
 * manifest, optionally the supersampled reference and a post-filter's output. */
#ifndef TT_HOST_SEQUENCE_H
#define TT_HOST_SEQUENCE_H

#include "session.h"

/* Length of the sub-pixel jitter cycle (thesis 5.5.1). */
#define TT__SEQ_JITTER_CYCLE 8u

/* Renders the sequence described by the options (scene, --sequence, --out-dir, ...). */
int tt__run_sequence(const tt__host_options *opt);

/* Downsamples `src` (sw x sh x 3, sw = w * scale) to w x h with a separable Blackman-Harris
 * filter of radius `radius` output pixels centred on the output pixel centres. */
void tt__downsample_bh(const float *src, uint32_t scale, uint32_t w, uint32_t h, float radius,
                       float *dst);

#endif
