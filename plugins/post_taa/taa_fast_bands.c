/* post_taa: the fast path's stage 2, the network by row bands (README.md, "How the fast
 * path works", 2): each band streams its rows through all layers; a body layer keeps only
 * the K rows its consumer reads, in a ring buffer per thread (cache resident), so nothing
 * but the input planes and the outputs touches the full frame. A band recomputes the halo
 * rows it shares with its neighbours (about 2 rows of work per band). Per row, the kernel
 * layer's 50 logits of 64-column chunks go to a small scratch buffer and the softmax, colour
 * mix (eq. 5.3), hidden layer, state and linear output follow at once on the same chunk.
 * Wide images are also cut into column tiles whose rings fit L2.
 *
 * With Winograd kernels (tt__net_kernels.wino, .wino4) the 5x5 layers with output blocks of
 * 10 or 12 (F(2x2, 5x5)) or 6, 10 or 12 (F(4x4, 5x5)) produce rows in pairs or quads at
 * absolute even rows / multiples of 4 (a band starting or ending inside one computes it
 * whole and keeps its own rows; rings hold the extra rows). Every output channel and pixel
 * is computed by the same operations in the same order whatever the band split, tile split
 * or thread count, so results do not depend on them (tests/taa_net.c checks it bit for
 * bit). The arithmetic is the kernels' (taa_kernel_*.c); this file only schedules. */
#include "taa_fast.h"

typedef struct tt__net_band_job {
  tt__net_state *s;
  const tt__net_model *m;
  const tt__net_kernels *kern; /* this frame's kernels */
  uint32_t set, band_rows, bands;
  uint32_t tile_cols, tiles, margin; /* column tiles: output columns per tile, count, and
                                       * the extra columns each side the body layers cover */
  uint32_t lw, rrs;                  /* ring row: columns computed, stride */
  float *out_rgb;
  size_t ring_off[TT__NET_MAX_LAYERS], logits_off;
  int wino;                            /* tt__net_state.winograd this frame (0 on the
                                       * portable path): 5x5 body layers after the first in
                                       * row pairs (1) or quads (2) */
  int kwino;                           /* kernel layer by Winograd: 2 F(2x2, 5x5) rows in
                                       * even pairs, 4 F(4x4, 5x5) rows in quads; 0 direct */
  size_t vbuf_off, mbuf_off, ebuf_off; /* Winograd scratch */
} tt__net_band_job;

/* Per-thread scratch header: accumulated ns of the stage's parts (tt__net_band_times). */
#define TT__NET_SCRATCH_HEADER 64u

/* One band's ring buffers and progress. */
typedef struct tt__net_band_ctx {
  const tt__net_band_job *job;
  unsigned char *scr;
  tt__net_band_times *tm;
  float *ring[TT__NET_MAX_LAYERS];
  uint32_t rlen[TT__NET_MAX_LAYERS];
  int next[TT__NET_MAX_LAYERS];
  int bx;            /* image column of ring column 0 */
  uint32_t tx0, tx1; /* the tile's output columns */
} tt__net_band_ctx;

/* Ring slot of row y (y may be negative). */
static inline float *tt__net_ring_row(const tt__net_band_ctx *b, uint32_t l, int y) {
  int R = (int)b->rlen[l];
  int k = ((y % R) + R) % R;
  return b->ring[l] + (size_t)k * b->job->rrs;
}

/* Body layer l can run as Winograd row pairs (5x5 with transformed weights, reading a
 * ring: not the first layer). */
static inline int tt__net_body_wino_ok(const tt__net_model *m, uint32_t l) {
  return l >= 1 && l < m->body_count && m->body[l].wino != NULL;
}

/* The same for F(4x4, 5x5) row quads. */
static inline int tt__net_body_wino4_ok(const tt__net_model *m, uint32_t l) {
  return l >= 1 && l < m->body_count && m->body[l].wino4 != NULL;
}

/* Rows body layer l (or, l == body_count, the kernel layer) produces at once with the
 * most capable algorithm: 4 (F(4x4, 5x5)), 2 (F(2x2, 5x5)) or 1. */
static uint32_t tt__net_max_step(const tt__net_model *m, uint32_t l) {
  if (l >= m->body_count) return m->kernel.wino4 ? 4u : m->kernel.wino ? 2u : 1u;
  return tt__net_body_wino4_ok(m, l) ? 4u : tt__net_body_wino_ok(m, l) ? 2u : 1u;
}

/* Rows in the ring of body layer l: what its consumer reads (the next body layer's or the
 * kernel layer's kernel size), one more when Winograd row pairs write or read it. The same
 * for both algorithms, so switching between frames keeps the scratch layout. */
static uint32_t tt__net_ring_len(const tt__net_model *m, uint32_t l) {
  int last = l + 1 >= m->body_count;
  uint32_t k = last ? m->kernel.ksize : m->body[l + 1].ksize;
  (void)last;
  /* the consumer's step S_c reads k + S_c - 1 rows; this layer, producing S_l rows at a
   * time, may be up to S_l - 1 rows ahead */
  return k + (tt__net_max_step(m, l + 1) - 1u) + (tt__net_max_step(m, l) - 1u);
}

/* Layer index of a set: the jitter set for 8-set layers. */
static inline uint32_t tt__net_set_of(const tt__net_layer *l, uint32_t set) {
  return l->sets > 1 ? set : 0;
}

/* Input row pointers of layer l (0: the input planes; else the previous ring) for output
 * row y; returns the channel stride. *col0: image column of the rows' column 0. */
static size_t tt__net_layer_rows(const tt__net_band_ctx *b, uint32_t l, uint32_t ksize, int y,
                                 const float **rowp, int *col0) {
  const tt__net_state *s = b->job->s;
  int r = (int)ksize / 2;
  if (l == 0) {
    for (int ky = 0; ky < (int)ksize; ky++)
      rowp[ky] = s->inp + (size_t)(y + ky - r + (int)s->halo) * s->inp_ys;
    *col0 = 0;
    return s->inp_cs;
  }
  for (int ky = 0; ky < (int)ksize; ky++) rowp[ky] = tt__net_ring_row(b, l - 1, y + ky - r);
  *col0 = b->bx;
  return (size_t)b->rlen[l - 1] * b->job->rrs;
}

/* Image columns [*xs, *xe) of the band's ring rows [bx, bx + lw); the rest is zero padding
 * (left of the image, right of it) and must read as 0 in the next layer. */
static void tt__net_band_image_cols(const tt__net_band_ctx *b, int *xs, int *xe) {
  int bx = b->bx, lw = (int)b->job->lw, vw = (int)b->job->s->vw;
  *xs = bx > 0 ? bx : 0;
  *xe = bx + lw < vw ? bx + lw : vw;
}

/* Zeroes the padding columns of one ring row (`out` channels `dcs` apart), given xs of
 * tt__net_band_image_cols. */
static void tt__net_zero_pad_cols(const tt__net_band_ctx *b, float *dst, size_t dcs, uint32_t out,
                                  int xs) {
  int bx = b->bx, lw = (int)b->job->lw, w = (int)b->job->s->width;
  int zr = w > xs ? w : xs; /* first column right of the image */
  for (uint32_t c = 0; c < out; c++) {
    float *d = dst + c * dcs + TT__NET_COL_OFF;
    if (xs > bx) memset(d, 0, (size_t)(xs - bx) * sizeof(float));
    if (zr < bx + lw) memset(d + (zr - bx), 0, (size_t)(bx + lw - zr) * sizeof(float));
  }
}

/* Computes row y of body layer l into its ring (zeros outside the image). */
static void tt__net_body_row(tt__net_band_ctx *b, uint32_t l, int y) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  float *dst = tt__net_ring_row(b, l, y);
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  if (y < 0 || y >= (int)s->height) {
    for (uint32_t c = 0; c < ly->out; c++) memset(dst + c * dcs, 0, rrs * sizeof(float));
    return;
  }
  double t0 = tt__net_now_ns();
  tt__net_conv_args a;
  int col0;
  a.cs = tt__net_layer_rows(b, l, ly->ksize, y, a.rowp, &col0);
  a.in = ly->in;
  a.ksize = ly->ksize;
  a.oblk = ly->oblk;
  a.nob = ly->nob;
  a.out = ly->out;
  uint32_t st = tt__net_set_of(ly, job->set);
  a.w = ly->wq + (size_t)st * ly->nob * ly->oblk * ly->in * ly->ksize * ly->ksize;
  a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
  a.dcs = dcs;
  a.relu = 1;
  a.pf = l == 0 && s->prefetch ? s->inp_ys : 0;
  int xs, xe;
  tt__net_band_image_cols(b, &xs, &xe);
  for (int x0 = xs; x0 < xe; x0 += (int)TT__NET_CHUNK) {
    a.x0 = (uint32_t)(x0 - col0);
    a.n = xe - x0 < (int)TT__NET_CHUNK ? (uint32_t)(xe - x0) : TT__NET_CHUNK;
    a.dst = dst + TT__NET_COL_OFF + (x0 - b->bx);
    job->kern->conv(&a);
  }
  tt__net_zero_pad_cols(b, dst, dcs, ly->out, xs);
  b->tm->body_ns += tt__net_now_ns() - t0;
}

/* Rows q, q + 1 (q even) of 5x5 body layer l >= 1 by Winograd into its ring (zeros
 * outside the image). */
static void tt__net_body_pair(tt__net_band_ctx *b, uint32_t l, int q) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  float *dst[2] = {tt__net_ring_row(b, l, q), tt__net_ring_row(b, l, q + 1)};
  int h = (int)s->height, inside[2] = {q >= 0 && q < h, q + 1 >= 0 && q + 1 < h};
  if (inside[0] || inside[1]) {
    double t0 = tt__net_now_ns();
    tt__net_wino_args a;
    for (int i = 0; i < 6; i++) a.rowp[i] = tt__net_ring_row(b, l - 1, q - 2 + i);
    a.cs = (size_t)b->rlen[l - 1] * rrs;
    a.in = ly->in;
    a.nob = ly->nob;
    a.out = ly->out;
    uint32_t st = tt__net_set_of(ly, job->set);
    a.u = ly->wino + (size_t)st * ly->nob * TT__NET_WINO_POS * ly->in * ly->oblk;
    a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
    a.dcs = dcs;
    a.relu = 1;
    a.vbuf = (float *)(b->scr + job->vbuf_off);
    a.mbuf = (float *)(b->scr + job->mbuf_off);
    int bx = b->bx, xs, xe;
    tt__net_band_image_cols(b, &xs, &xe);
    for (int x0 = xs; x0 < xe; x0 += (int)TT__NET_CHUNK) {
      a.x0 = (uint32_t)(x0 - bx);
      a.n = xe - x0 < (int)TT__NET_CHUNK ? (uint32_t)(xe - x0) : TT__NET_CHUNK;
      a.dst[0] = dst[0] + TT__NET_COL_OFF + (x0 - bx);
      a.dst[1] = dst[1] + TT__NET_COL_OFF + (x0 - bx);
      job->kern->wino(&a, ly->oblk);
    }
    for (int r = 0; r < 2; r++) tt__net_zero_pad_cols(b, dst[r], dcs, ly->out, xs);
    b->tm->body_ns += tt__net_now_ns() - t0;
  }
  for (int r = 0; r < 2; r++)
    if (!inside[r])
      for (uint32_t c = 0; c < ly->out; c++) memset(dst[r] + c * dcs, 0, rrs * sizeof(float));
}

/* Rows q .. q + 3 (q a multiple of 4) of 5x5 body layer l >= 1 by F(4x4, 5x5) into its
 * ring (zeros outside the image). */
static void tt__net_body_quad(tt__net_band_ctx *b, uint32_t l, int q) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  float *dst[4];
  int h = (int)s->height, inside[4], any = 0;
  for (int r = 0; r < 4; r++) {
    dst[r] = tt__net_ring_row(b, l, q + r);
    inside[r] = q + r >= 0 && q + r < h;
    any |= inside[r];
  }
  if (any) {
    double t0 = tt__net_now_ns();
    tt__net_wino4_args a;
    for (int i = 0; i < 8; i++) a.rowp[i] = tt__net_ring_row(b, l - 1, q - 2 + i);
    a.cs = (size_t)b->rlen[l - 1] * rrs;
    a.in = ly->in;
    a.nob = ly->nob;
    a.out = ly->out;
    uint32_t st = tt__net_set_of(ly, job->set);
    a.u = ly->wino4 + (size_t)st * ly->nob * TT__NET_WINO4_POS * ly->in * ly->oblk;
    a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
    a.dcs = dcs;
    a.relu = 1;
    a.vbuf = (float *)(b->scr + job->vbuf_off);
    a.mbuf = (float *)(b->scr + job->mbuf_off);
    a.ebuf = (float *)(b->scr + job->ebuf_off);
    int bx = b->bx, xs, xe;
    tt__net_band_image_cols(b, &xs, &xe);
    for (int x0 = xs; x0 < xe; x0 += (int)TT__NET_CHUNK) {
      a.x0 = (uint32_t)(x0 - bx);
      a.n = xe - x0 < (int)TT__NET_CHUNK ? (uint32_t)(xe - x0) : TT__NET_CHUNK;
      for (int r = 0; r < 4; r++) a.dst[r] = dst[r] + TT__NET_COL_OFF + (x0 - bx);
      job->kern->wino4(&a, ly->oblk);
    }
    for (int r = 0; r < 4; r++) tt__net_zero_pad_cols(b, dst[r], dcs, ly->out, xs);
    b->tm->body_ns += tt__net_now_ns() - t0;
  }
  for (int r = 0; r < 4; r++)
    if (!inside[r])
      for (uint32_t c = 0; c < ly->out; c++) memset(dst[r] + c * dcs, 0, rrs * sizeof(float));
}

/* Rows body layer l computes at once this frame: 4 (F(4x4, 5x5)), 2 (F(2x2, 5x5)) or 1. */
static inline int tt__net_body_step(const tt__net_band_job *job, uint32_t l) {
  if (job->wino >= 2 && job->kern->wino4 && tt__net_body_wino4_ok(job->m, l)) return 4;
  return job->wino && tt__net_body_wino_ok(job->m, l) ? 2 : 1;
}

/* Makes body layer l hold rows up to y (computing the inputs first). */
static void tt__net_ensure_rows(tt__net_band_ctx *b, uint32_t l, int y) {
  int step = tt__net_body_step(b->job, l);
  while (b->next[l] <= y) {
    int yy = b->next[l];
    if (l > 0) tt__net_ensure_rows(b, l - 1, yy + step - 1 + (int)b->job->m->body[l].ksize / 2);
    if (step == 4) tt__net_body_quad(b, l, yy);
    else if (step == 2) tt__net_body_pair(b, l, yy);
    else tt__net_body_row(b, l, yy);
    b->next[l] += step;
  }
}

/* The colour-mix arguments shared by every row of a band (the hidden layer's weight set,
 * the ring of the last body layer, the output image). */
static void tt__net_mix_setup(const tt__net_band_ctx *b, tt__net_mix_args *mx) {
  const tt__net_band_job *job = b->job;
  const tt__net_model *m = job->m;
  uint32_t last = m->body_count - 1;
  mx->s = job->s;
  mx->m = m;
  mx->hcs = (size_t)b->rlen[last] * job->rrs;
  mx->hx = b->bx;
  uint32_t hs = tt__net_set_of(&m->hid, job->set);
  mx->hw = m->hidden ? m->hid.w + (size_t)hs * m->hid.out * m->hid.in : NULL;
  mx->hb = m->hidden ? m->hid.b + (size_t)hs * m->hid.out : NULL;
  mx->out_rgb = job->out_rgb;
}

/* Kernel layer, softmax, colour mix, hidden layer and outputs of row y. */
static void tt__net_head_row(tt__net_band_ctx *b, int y) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  tt__net_conv_args a;
  int col0;
  a.cs = tt__net_layer_rows(b, m->body_count, kl->ksize, y, a.rowp, &col0);
  a.in = kl->in;
  a.ksize = kl->ksize;
  a.oblk = kl->oblk;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = tt__net_set_of(kl, job->set);
  a.w = kl->wq + (size_t)ks * kl->nob * kl->oblk * kl->in * kl->ksize * kl->ksize;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  a.dcs = TT__NET_CHUNK;
  a.relu = 0;
  a.pf = 0;
  a.dst = (float *)(b->scr + job->logits_off);
  tt__net_mix_args mx;
  tt__net_mix_setup(b, &mx);
  mx.lg = a.dst;
  mx.y = (uint32_t)y;
  mx.hrow = tt__net_ring_row(b, last, y);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += TT__NET_CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < TT__NET_CHUNK ? b->tx1 - x0 : TT__NET_CHUNK;
    double t0 = tt__net_now_ns();
    job->kern->conv(&a);
    double t1 = tt__net_now_ns();
    job->kern->mix(&mx);
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += tt__net_now_ns() - t1;
  }
}

/* Winograd kernel layer of rows p, p + 1 (p even), then the head of those in [y0, y1). */
static void tt__net_head_pair(tt__net_band_ctx *b, int p, uint32_t y0, uint32_t y1) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  tt__net_wino_args a;
  for (int i = 0; i < 6; i++) a.rowp[i] = tt__net_ring_row(b, last, p - 2 + i);
  a.cs = (size_t)b->rlen[last] * job->rrs;
  int col0 = b->bx;
  a.in = kl->in;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = tt__net_set_of(kl, job->set);
  a.u = kl->wino + (size_t)ks * kl->nob * TT__NET_WINO_POS * kl->in * kl->oblk;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  float *lg = (float *)(b->scr + job->logits_off);
  size_t lgn = (size_t)kl->nob * kl->oblk * TT__NET_CHUNK;
  a.dst[0] = lg;
  a.dst[1] = lg + lgn;
  a.dcs = TT__NET_CHUNK;
  a.relu = 0;
  a.vbuf = (float *)(b->scr + job->vbuf_off);
  a.mbuf = (float *)(b->scr + job->mbuf_off);
  tt__net_mix_args mx;
  tt__net_mix_setup(b, &mx);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += TT__NET_CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < TT__NET_CHUNK ? b->tx1 - x0 : TT__NET_CHUNK;
    double t0 = tt__net_now_ns();
    job->kern->wino(&a, kl->oblk);
    double t1 = tt__net_now_ns();
    for (int r = 0; r < 2; r++) {
      int y = p + r;
      if (y < (int)y0 || y >= (int)y1 || y >= (int)s->height) continue;
      mx.lg = a.dst[r];
      mx.y = (uint32_t)y;
      mx.hrow = tt__net_ring_row(b, last, y);
      job->kern->mix(&mx);
    }
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += tt__net_now_ns() - t1;
  }
}

/* F(4x4, 5x5) kernel layer of rows p .. p + 3 (p a multiple of 4), then the head of those
 * in [y0, y1). */
static void tt__net_head_quad(tt__net_band_ctx *b, int p, uint32_t y0, uint32_t y1) {
  const tt__net_band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  tt__net_wino4_args a;
  for (int i = 0; i < 8; i++) a.rowp[i] = tt__net_ring_row(b, last, p - 2 + i);
  a.cs = (size_t)b->rlen[last] * job->rrs;
  int col0 = b->bx;
  a.in = kl->in;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = tt__net_set_of(kl, job->set);
  a.u = kl->wino4 + (size_t)ks * kl->nob * TT__NET_WINO4_POS * kl->in * kl->oblk;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  float *lg = (float *)(b->scr + job->logits_off);
  size_t lgn = (size_t)kl->nob * kl->oblk * TT__NET_CHUNK;
  for (int r = 0; r < 4; r++) a.dst[r] = lg + r * lgn;
  a.dcs = TT__NET_CHUNK;
  a.relu = 0;
  a.vbuf = (float *)(b->scr + job->vbuf_off);
  a.mbuf = (float *)(b->scr + job->mbuf_off);
  a.ebuf = (float *)(b->scr + job->ebuf_off);
  tt__net_mix_args mx;
  tt__net_mix_setup(b, &mx);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += TT__NET_CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < TT__NET_CHUNK ? b->tx1 - x0 : TT__NET_CHUNK;
    double t0 = tt__net_now_ns();
    job->kern->wino4(&a, kl->oblk);
    double t1 = tt__net_now_ns();
    for (int r = 0; r < 4; r++) {
      int y = p + r;
      if (y < (int)y0 || y >= (int)y1 || y >= (int)s->height) continue;
      mx.lg = a.dst[r];
      mx.y = (uint32_t)y;
      mx.hrow = tt__net_ring_row(b, last, y);
      job->kern->mix(&mx);
    }
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += tt__net_now_ns() - t1;
  }
}

/* Rows [y0, y1) of columns [tx0, tx1) through all layers. */
static void tt__net_band_run(const tt__net_band_job *job, uint32_t thread, uint32_t y0, uint32_t y1,
                             uint32_t tx0, uint32_t tx1) {
  tt__net_band_ctx b;
  memset(&b, 0, sizeof b);
  b.job = job;
  b.tx0 = tx0;
  b.tx1 = tx1;
  b.bx = (int)tx0 - (int)job->margin;
  b.scr = (unsigned char *)job->s->scratch + (size_t)thread * job->s->scratch_bytes;
  b.tm = (tt__net_band_times *)b.scr;
  const tt__net_model *m = job->m;
  int rk = (int)m->kernel.ksize / 2;
  /* First row of each layer, from the kernel layer back: the first row its consumer's
   * first step reads, rounded down to the layer's own step (pairs on even rows, quads on
   * multiples of 4). Every row a Winograd tile reads is then computed in this band: the
   * tile's transforms mix all of its input rows (exact only in exact arithmetic), so a
   * stale ring row would change its outputs in the last bits. */
  uint32_t ys = job->kwino == 4 ? y0 & ~3u : job->kwino ? y0 & ~1u : y0;
  int need = (int)ys - rk;
  for (uint32_t l = m->body_count; l-- > 0;) {
    b.ring[l] = (float *)(b.scr + job->ring_off[l]);
    b.rlen[l] = tt__net_ring_len(m, l);
    int v = need & ~(tt__net_body_step(job, l) - 1);
    b.next[l] = v;
    need = v - (int)m->body[l].ksize / 2;
  }
  if (job->kwino == 4) {
    /* Row quads at absolute multiples of 4; a band starting or ending inside a quad
     * computes it whole and keeps its own rows. */
    for (int p = (int)(y0 & ~3u); p < (int)y1; p += 4) {
      tt__net_ensure_rows(&b, m->body_count - 1, p + 3 + rk);
      tt__net_head_quad(&b, p, y0, y1);
    }
    return;
  }
  if (job->kwino) {
    /* Row pairs at absolute even rows; a band starting or ending on an odd row computes
     * its first / last pair whole and keeps its own row. */
    for (int p = (int)(y0 & ~1u); p < (int)y1; p += 2) {
      tt__net_ensure_rows(&b, m->body_count - 1, p + 1 + rk);
      tt__net_head_pair(&b, p, y0, y1);
    }
    return;
  }
  for (int y = (int)y0; y < (int)y1; y++) {
    tt__net_ensure_rows(&b, m->body_count - 1, y + rk);
    tt__net_head_row(&b, y);
  }
}

static void tt__net_band_body(void *ctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  const tt__net_band_job *job = ctx;
  uint32_t h = job->s->height;
  if (thread_index >= job->s->scratch_threads) thread_index = 0; /* not expected */
  for (uint64_t k = begin; k < end; k++) {
    uint32_t band = (uint32_t)(k / job->tiles), tile = (uint32_t)(k % job->tiles);
    uint32_t y0 = band * job->band_rows, y1 = y0 + job->band_rows;
    uint32_t x0 = tile * job->tile_cols, x1 = x0 + job->tile_cols;
    tt__net_band_run(job, thread_index, y0, y1 < h ? y1 : h, x0, x1 < job->s->vw ? x1 : job->s->vw);
  }
}

/* Scratch layout for `threads` threads; (re)allocates when it grew. */
static tt_status tt__net_fast_scratch(tt__net_state *s, const tt__net_model *m,
                                      tt__net_band_job *job, uint32_t threads) {
  /* Column tiles keep the ring buffers within ~512 KB (L2): a tile's body layers cover 16
   * more columns each side (>= the receptive field's 2..12), recomputed by both tiles. */
  size_t ring_ch = 0;
  for (uint32_t l = 0; l < m->body_count; l++)
    ring_ch += (size_t)m->body[l].out * tt__net_ring_len(m, l);
  uint32_t cols = s->tile_cols;
  if (!cols) {
    size_t fit = (512u * 1024u) / (ring_ch * sizeof(float));
    cols = s->vw;
    if (fit < s->vw + 2 * TT__NET_COL_OFF) {
      uint32_t tiles = (uint32_t)((s->vw + fit - 1) / (fit > 128 ? fit - 64 : 64));
      cols = (s->vw + tiles - 1) / tiles;
    }
  }
  cols = (cols + 63) & ~63u;
  if (cols >= s->vw) cols = s->vw;
  job->tile_cols = cols;
  job->tiles = (s->vw + cols - 1) / cols;
  job->margin = job->tiles > 1 ? 16u : 0u;
  job->lw = cols + 2 * job->margin;
  job->rrs = job->lw + 2 * TT__NET_COL_OFF;
  size_t off = TT__NET_SCRATCH_HEADER;
  for (uint32_t l = 0; l < m->body_count; l++) {
    uint32_t R = tt__net_ring_len(m, l);
    job->ring_off[l] = off;
    off += ((size_t)m->body[l].out * R * job->rrs * sizeof(float) + 63) & ~(size_t)63;
  }
  job->logits_off = off;
  off += 4 * (size_t)m->kernel.nob * m->kernel.oblk * TT__NET_CHUNK * sizeof(float); /* 4 rows */
  /* Winograd scratch (every such layer reads W channels, blocks of <= 12 outputs). */
  job->vbuf_off = job->mbuf_off = job->ebuf_off = 0;
  int any = m->kernel.wino != NULL;
  for (uint32_t l = 0; l < m->body_count; l++)
    any |= tt__net_body_wino_ok(m, l) | tt__net_body_wino4_ok(m, l);
  if (any) {
    /* F(2x2, 5x5): V 36 x W x 16, M 2 x 36 x 12 x 16; F(4x4, 5x5): V 64 x W x 16, M 64 x
     * 12 x 16, E 64 x 16 (all offsets 64-byte aligned) */
    size_t v2 = (size_t)TT__NET_WINO_POS * m->width * 16,
           v4 = (size_t)TT__NET_WINO4_POS * m->width * 16;
    job->vbuf_off = off;
    off += ((v2 > v4 ? v2 : v4) * sizeof(float) + 63) & ~(size_t)63;
    job->mbuf_off = off;
    off += 2 * (size_t)TT__NET_WINO_POS * 12 * 16 * sizeof(float); /* >= 64 x 12 x 16 */
    job->ebuf_off = off;
    off += (size_t)TT__NET_WINO4_POS * 16 * sizeof(float);
  }
  off = (off + 4095) & ~(size_t)4095; /* threads' blocks on separate pages */
  if (s->scratch && s->scratch_threads >= threads && s->scratch_bytes == off) return TT_OK;
  free(s->scratch);
  s->scratch = aligned_alloc(4096, off * threads);
  if (!s->scratch) {
    s->scratch_threads = 0;
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for scratch");
  }
  /* Ring columns outside the image stay zero: only [TT__NET_COL_OFF, TT__NET_COL_OFF + vw) is ever written. */
  memset(s->scratch, 0, off * threads);
  s->scratch_threads = threads;
  s->scratch_bytes = off;
  return TT_OK;
}

tt_status tt__net_fast_bands(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                             const tt__net_kernels *k, uint32_t set, float *out_rgb,
                             tt__net_band_times *times) {
  int pool = host && host->parallel_for && s->height >= 16;
  uint32_t threads = pool && host->thread_count ? host->thread_count() : 1;
  if (threads < 1) threads = 1;
  tt__net_band_job job = {.s = s, .m = m, .kern = k, .set = set, .out_rgb = out_rgb};
  job.wino = k->wino ? s->winograd : 0;
  job.kwino = !job.wino || !m->kernel.wino                      ? 0
              : s->winograd >= 2 && m->kernel.wino4 && k->wino4 ? 4
                                                                : 2;
  tt_status st = tt__net_fast_scratch(s, m, &job, threads);
  if (st != TT_OK) return st;
  for (uint32_t t = 0; t < s->scratch_threads; t++)
    memset((unsigned char *)s->scratch + (size_t)t * s->scratch_bytes, 0,
           sizeof(tt__net_band_times));
  /* Bands: about 4 per thread (dynamic scheduling evens out a loaded machine), at least 16
   * rows each (a band recomputes ~2 rows of halo work). The split does not change results. */
  uint32_t rows = s->band_rows;
  if (!rows) {
    rows = (s->height + 4 * threads - 1) / (4 * threads);
    if (rows < 16) rows = 16;
    if (job.wino) rows = (rows + 3) & ~3u; /* whole Winograd row pairs / quads per band */
  }
  job.band_rows = rows;
  job.bands = (s->height + rows - 1) / rows;
  uint64_t items = (uint64_t)job.bands * job.tiles;
  if (!pool || threads == 1 || items == 1 ||
      host->parallel_for(items, 1, tt__net_band_body, &job) != TT_OK)
    tt__net_band_body(&job, 0, items, 0); /* serial, or finishing an interrupted frame */
  memset(times, 0, sizeof *times);
  for (uint32_t t = 0; t < s->scratch_threads; t++) {
    const tt__net_band_times *bt =
        (const tt__net_band_times *)((unsigned char *)s->scratch + (size_t)t * s->scratch_bytes);
    times->body_ns += bt->body_ns;
    times->kernel_ns += bt->kernel_ns;
    times->mix_ns += bt->mix_ns;
  }
  return TT_OK;
}
