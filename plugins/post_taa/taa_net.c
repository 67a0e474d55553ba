/* post_taa: the thesis' kernel-prediction TAA network (chapter 5.4, Fig. 5.2) in C.
 *
 * Per frame: tonemap the new colour, reproject the previous state [rgb, hidden] with
 * Catmull-Rom along the motion vectors, run the body convolutions (ReLU, zero padding),
 * then per pixel the 5x5 kernel layer (softmax over the 2 x 25 weights), the colour mix of
 * eq. 5.3 over the new frame and the reprojected output, and the 1x1 hidden-state layer.
 * Layers whose file record has 8 weight sets use set (jitter_index mod 8).
 *
 * This file reads the weights file (format in README.md) and holds the reference path:
 * plain scalar loops over the file's PyTorch layout on HWC planes with a zero border of 2
 * pixels (double accumulation, libm expf), used when `reference` is set, i.e. by the tests
 * to check the fast path. Every other frame goes to taa_net_fast.c (banded, SIMD). */
#include <tunetrace/file.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/camera.h>

#include "taa_internal.h"

#include <tt_util/hash.h>

/* ---- weights file ---- */

/* Reads a little-endian u32 (the format is LE whatever the host). */
static uint32_t tt__net_u32(const unsigned char *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Reads a little-endian IEEE float. */
static float tt__net_f32(const unsigned char *p) {
  uint32_t u = tt__net_u32(p);
  float f;
  memcpy(&f, &u, 4);
  return f;
}

/* FNV-1a 32-bit over the payload (<tt_util/hash.h>): cheap and catches torn or edited
 * files. */
static uint32_t tt__net_fnv1a(const unsigned char *p, size_t n) { return tt__fnv1a32(p, n); }

/* 32-byte aligned zeroed floats. */
static float *tt__net_alloc(size_t count) {
  size_t bytes = (count * sizeof(float) + 31) & ~(size_t)31;
  float *p = aligned_alloc(32, bytes ? bytes : 32);
  if (p) memset(p, 0, bytes ? bytes : 32);
  return p;
}

/* Frees one layer's arrays. */
static void tt__net_layer_free(tt__net_layer *l) {
  free(l->w);
  free(l->b);
  free(l->wq);
  free(l->bq);
  memset(l, 0, sizeof *l);
}

void tt__net_free(tt__net_model *m) {
  for (uint32_t i = 0; i < TT__NET_MAX_LAYERS; i++) tt__net_layer_free(&m->body[i]);
  tt__net_layer_free(&m->kernel);
  tt__net_layer_free(&m->hid);
}

/* Copies weights from the payload and repacks them for the fast path. */
static tt_status tt__net_layer_read(tt__net_layer *l, const unsigned char *p, const char *src) {
  size_t per = (size_t)l->out * l->in * l->ksize * l->ksize;
  l->w = tt__net_alloc(per * l->sets);
  l->b = tt__net_alloc((size_t)l->out * l->sets);
  if (!l->w || !l->b)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory for weights", src);
  for (size_t i = 0; i < per * l->sets; i++) l->w[i] = tt__net_f32(p + 4 * i);
  p += 4 * per * l->sets;
  for (size_t i = 0; i < (size_t)l->out * l->sets; i++) l->b[i] = tt__net_f32(p + 4 * i);
  return tt__net_fast_pack(l);
}

#define TT__NET_HEADER_FIXED                                                                       \
  48u /* magic 8, version, header size, 6 counts, motion scale, 2 reserved */
#define TT__NET_LAYER_RECORD 24u /* role, in, out, ksize, sets, activation */

tt_status tt__net_parse(const void *data, size_t size, const char *src, tt__net_model *m) {
  const unsigned char *p = data;
  memset(m, 0, sizeof *m);
  if (size < 12 || memcmp(p, TT__NET_MAGIC, 8) != 0)
    return tt_set_error(TT_ERR_PARSE,
                        "%s: not a post_taa weights file (bad magic; expected \"TTAANET\")", src);
  uint32_t version = tt__net_u32(p + 8);
  if (version < 1 || version > TT__NET_VERSION)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: weights format version %u is not supported (this build reads "
                        "versions 1 to %u)",
                        src, version, TT__NET_VERSION);
  if (size < TT__NET_HEADER_FIXED)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated header (%zu bytes, expected at least %u)", src,
                        size, TT__NET_HEADER_FIXED);
  uint32_t header_bytes = tt__net_u32(p + 12);
  m->in_channels = tt__net_u32(p + 16);
  m->width = tt__net_u32(p + 20);
  m->hidden = tt__net_u32(p + 24);
  uint32_t mix_k = tt__net_u32(p + 28), jitter_sets = tt__net_u32(p + 32);
  uint32_t layers = tt__net_u32(p + 36);
  m->motion_scale = tt__net_f32(p + 40);
  m->flags = version >= 2 ? tt__net_u32(p + 44) : 0; /* reserved (ignored) in version 1 */
  const uint32_t known = TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET;
  if ((m->flags & ~known) || ((m->flags & TT__NET_FLAG_RESET) && !(m->flags & TT__NET_FLAG_REJECT)))
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: input flags 0x%x (this build knows 0x1 "
                        "rejection input, 0x2 history reset with it)",
                        src, m->flags);
  uint32_t want_in = 9 + m->hidden + ((m->flags & TT__NET_FLAG_REJECT) ? 1u : 0u);
  if (mix_k != TT__NET_MIX_K || jitter_sets != TT__NET_JITTER_SETS)
    return tt_set_error(TT_ERR_PARSE,
                        "%s: colour-mix kernel %u and jitter sets %u (expected "
                        "%u and %u)",
                        src, mix_k, jitter_sets, TT__NET_MIX_K, TT__NET_JITTER_SETS);
  if (m->hidden > 8 || m->in_channels != want_in || m->width < 1 || m->width > TT__NET_MAX_CH ||
      !isfinite(m->motion_scale))
    return tt_set_error(TT_ERR_PARSE,
                        "%s: bad model shape: in %u, width %u, hidden %u, "
                        "flags 0x%x (in must be 9 + hidden, + 1 with the rejection input; "
                        "hidden <= 8, width in [1, %u])",
                        src, m->in_channels, m->width, m->hidden, m->flags, TT__NET_MAX_CH);
  uint32_t want_layers_min = 2 + (m->hidden ? 1 : 0);
  if (layers < want_layers_min || layers > TT__NET_MAX_LAYERS)
    return tt_set_error(TT_ERR_PARSE, "%s: %u layers (expected %u to %u)", src, layers,
                        want_layers_min, TT__NET_MAX_LAYERS);
  if (header_bytes != TT__NET_HEADER_FIXED + layers * TT__NET_LAYER_RECORD)
    return tt_set_error(TT_ERR_PARSE, "%s: header size %u does not match %u layers", src,
                        header_bytes, layers);
  if (size < header_bytes)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated layer table (%zu bytes, expected %u)", src,
                        size, header_bytes);
  /* Validate every record and the chain of shapes before reading any payload. */
  size_t payload = 0;
  uint32_t prev_out = m->in_channels;
  int seen_kernel = 0, seen_hidden = 0;
  tt__net_layer recs[TT__NET_MAX_LAYERS];
  uint32_t roles[TT__NET_MAX_LAYERS];
  for (uint32_t i = 0; i < layers; i++) {
    const unsigned char *r = p + TT__NET_HEADER_FIXED + i * TT__NET_LAYER_RECORD;
    tt__net_layer *l = &recs[i];
    memset(l, 0, sizeof *l);
    roles[i] = tt__net_u32(r);
    l->in = tt__net_u32(r + 4);
    l->out = tt__net_u32(r + 8);
    l->ksize = tt__net_u32(r + 12);
    l->sets = tt__net_u32(r + 16);
    l->activation = tt__net_u32(r + 20);
    const char *what = roles[i] == 1 ? "body" : roles[i] == 2 ? "kernel" : "hidden";
    if (roles[i] < 1 || roles[i] > 3)
      return tt_set_error(TT_ERR_PARSE, "%s: layer %u: unknown role %u", src, i, roles[i]);
    if ((l->sets != 1 && l->sets != TT__NET_JITTER_SETS) || l->ksize % 2 == 0 ||
        l->ksize > 2 * TT__NET_BORDER + 1 || l->out == 0 || l->out > TT__NET_MAX_CH)
      return tt_set_error(TT_ERR_PARSE,
                          "%s: layer %u (%s): sets %u, kernel %u, out %u "
                          "(sets 1 or 8, odd kernel <= 5, out <= %u)",
                          src, i, what, l->sets, l->ksize, l->out, TT__NET_MAX_CH);
    if (roles[i] == 1) {
      if (seen_kernel || seen_hidden || l->in != prev_out || l->out != m->width ||
          l->activation != 1)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: layer %u (body): %u -> %u, activation %u "
                            "(expected %u -> %u ReLU, before the kernel layer)",
                            src, i, l->in, l->out, l->activation, prev_out, m->width);
      prev_out = l->out;
      m->body_count++;
    } else if (roles[i] == 2) {
      if (seen_kernel || l->in != m->width || l->out != 2 * TT__NET_MIX_TAPS ||
          l->activation != 2 || m->body_count == 0)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: layer %u (kernel): %u -> %u, activation %u "
                            "(expected %u -> %u softmax after the body)",
                            src, i, l->in, l->out, l->activation, m->width, 2 * TT__NET_MIX_TAPS);
      seen_kernel = 1;
    } else {
      if (seen_hidden || l->in != m->width || l->out != m->hidden || l->ksize != 1 ||
          l->activation != 0 || m->hidden == 0 || m->body_count == 0)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: layer %u (hidden): %u -> %u, kernel %u "
                            "(expected %u -> %u, 1x1, no activation)",
                            src, i, l->in, l->out, l->ksize, m->width, m->hidden);
      seen_hidden = 1;
    }
    payload += 4 * ((size_t)l->sets * l->out * (l->in * l->ksize * l->ksize + 1));
  }
  if (!seen_kernel || (m->hidden && !seen_hidden))
    return tt_set_error(TT_ERR_PARSE, "%s: missing %s layer", src,
                        !seen_kernel ? "kernel" : "hidden");
  size_t want = header_bytes + payload + 4;
  if (size < want)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated: %zu bytes, the layer table needs %zu", src,
                        size, want);
  if (size > want)
    return tt_set_error(TT_ERR_PARSE, "%s: %zu trailing bytes after the checksum", src,
                        size - want);
  uint32_t sum = tt__net_fnv1a(p + header_bytes, payload);
  if (sum != tt__net_u32(p + header_bytes + payload))
    return tt_set_error(TT_ERR_PARSE, "%s: checksum mismatch (file corrupted)", src);
  const unsigned char *q = p + header_bytes;
  uint32_t b = 0;
  for (uint32_t i = 0; i < layers; i++) {
    tt__net_layer *dst = roles[i] == 1 ? &m->body[b++] : roles[i] == 2 ? &m->kernel : &m->hid;
    *dst = recs[i];
    tt_status st = tt__net_layer_read(dst, q, src);
    if (st != TT_OK) {
      tt__net_free(m);
      return st;
    }
    q += 4 * ((size_t)dst->sets * dst->out * (dst->in * dst->ksize * dst->ksize + 1));
  }
  return TT_OK;
}

tt_status tt__net_load(const char *path, tt__net_model *m) {
  memset(m, 0, sizeof *m);
  /* the shared reader refuses a directory, FIFO or device (a directory used to ask for
   * ~LONG_MAX bytes) and caps the size far above any network this plugin runs */
  char *buf;
  size_t n;
  if (tt_file_read(path, "weights file", (size_t)64 << 20, &buf, &n) != TT_OK) return TT_ERR_IO;
  if (n == 0) {
    tt_free(buf);
    return tt_set_error(TT_ERR_PARSE, "%s: empty weights file", path);
  }
  tt_status st = tt__net_parse((const unsigned char *)buf, n, path, m);
  tt_free(buf);
  return st;
}

/* ---- state ---- */

tt_status tt__net_state_init(tt__net_state *s, const tt__net_model *m, uint32_t width,
                             uint32_t height) {
  memset(s, 0, sizeof *s);
  s->width = width;
  s->height = height;
  s->state_ch = 3 + m->hidden;
  uint32_t ch = m->in_channels > m->width ? m->in_channels : m->width;
  s->plane_stride = ch;
  size_t px = (size_t)width * height;
  /* + 4 floats: the fast path reads a state pixel as one 4-float vector (3 channels + the
   * next pixel's first, unused), also for the last pixel */
  s->state = tt__net_alloc(px * s->state_ch + 4);
  s->next_state = tt__net_alloc(px * s->state_ch + 4);
  int rej_ok = 1;
  if (m->flags & TT__NET_FLAG_REJECT) {
    s->prev_depth = tt__net_alloc(px);
    s->reject = malloc(2 * px);
    rej_ok = s->prev_depth && s->reject;
  }
  if (!s->state || !s->next_state || !rej_ok || tt__net_fast_init(s, m) != TT_OK) {
    tt__net_state_free(s);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY,
                        TT__TAA_NAME ": out of memory for %ux%u "
                                     "network planes",
                        width, height);
  }
  return TT_OK;
}

/* The reference path's padded HWC planes, allocated on its first use. */
static tt_status tt__net_reference_planes(tt__net_state *s) {
  if (s->planes[0]) return TT_OK;
  size_t ch = s->plane_stride;
  size_t ppx = (size_t)(s->width + 2 * TT__NET_BORDER) * (s->height + 2 * TT__NET_BORDER);
  s->planes[0] = tt__net_alloc(ppx * ch + 8);
  s->planes[1] = tt__net_alloc(ppx * ch + 8);
  s->tm = tt__net_alloc(ppx * 3);
  s->reproj = tt__net_alloc(ppx * 3);
  if (!s->planes[0] || !s->planes[1] || !s->tm || !s->reproj)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for the "
                                                           "reference planes");
  return TT_OK;
}

void tt__net_state_free(tt__net_state *s) {
  free(s->prev_depth);
  free(s->reject);
  free(s->state);
  free(s->next_state);
  free(s->planes[0]);
  free(s->planes[1]);
  free(s->tm);
  free(s->reproj);
  tt__net_fast_free(s);
  memset(s, 0, sizeof *s);
}

/* ---- per-frame passes ---- */

typedef struct tt__net_job {
  tt__net_state *s;
  const tt__net_model *m;
  const float *color, *depth, *motion;
  const uint8_t *reject; /* rejection mask, or NULL (model without the input) */
  float depth_scale;
  uint32_t set;
  const tt__net_layer *layer;
  const float *in_plane;
  float *out_plane;
  float *out_rgb;
} tt__net_job;

/* Padded plane index of pixel (x, y). */
static inline size_t tt__net_pidx(const tt__net_state *s, uint32_t x, uint32_t y) {
  return (size_t)(y + TT__NET_BORDER) * (s->width + 2 * TT__NET_BORDER) + x + TT__NET_BORDER;
}

/* Builds the network input (plane 0), the tonemapped colour and the reprojected RGB. */
static void tt__net_input_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__net_job *job = ctx;
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t w = s->width, sc = s->state_ch;
  float fb[16];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x, pi = tt__net_pidx(s, x, y);
      float *in = s->planes[0] + pi * s->plane_stride;
      float t[3];
      tt__taa_tonemap(job->color + 3 * i, t);
      memcpy(s->tm + 3 * pi, t, sizeof t);
      float mx = job->motion ? job->motion[2 * i] : 0.0f;
      float my = job->motion ? job->motion[2 * i + 1] : 0.0f;
      uint8_t rj = job->reject ? job->reject[i] : 0;
      if (s->valid && !((rj & TT__TAA_REJECT_RESET) && (m->flags & TT__NET_FLAG_RESET))) {
        /* Motion points from this frame back to the previous one (film.h). */
        tt__taa_sample_catmull_rom(s->state, w, s->height, sc, (float)x + 0.5f + mx,
                                   (float)y + 0.5f + my, fb);
      } else {
        /* No history: the new frame stands in for the previous output, hidden = 0 (the
         * training script starts every window the same way). */
        memset(fb, 0, sizeof fb);
        memcpy(fb, t, sizeof t);
      }
      in[0] = t[0];
      in[1] = t[1];
      in[2] = t[2];
      in[3] = mx * m->motion_scale;
      in[4] = my * m->motion_scale;
      in[5] = job->depth ? job->depth[i] * job->depth_scale : 0.0f;
      for (uint32_t c = 0; c < sc; c++) in[6 + c] = fb[c];
      if (job->reject) in[6 + sc] = (rj & TT__TAA_REJECT_RAW) ? 1.0f : 0.0f;
      memcpy(s->reproj + 3 * pi, fb, 3 * sizeof(float));
    }
}

/* Plain scalar reference of one convolution on padded planes (file layout, no packing). */
static void tt__net_ref_conv(const tt__net_state *s, const tt__net_layer *l, uint32_t set,
                             const float *in_plane, uint32_t x, uint32_t y, float *out) {
  int r = (int)l->ksize / 2;
  uint32_t wp = s->width + 2 * TT__NET_BORDER;
  const float *w = l->w + (size_t)set * l->out * l->in * l->ksize * l->ksize;
  for (uint32_t o = 0; o < l->out; o++) {
    double a = l->b[set * l->out + o];
    for (uint32_t c = 0; c < l->in; c++)
      for (int ky = 0; ky < (int)l->ksize; ky++)
        for (int kx = 0; kx < (int)l->ksize; kx++) {
          size_t q = (size_t)((int)y + TT__NET_BORDER + ky - r) * wp +
                     (size_t)((int)x + TT__NET_BORDER + kx - r);
          a += (double)w[((o * l->in + c) * l->ksize + ky) * l->ksize + kx] *
               in_plane[q * s->plane_stride + c];
        }
    out[o] = (float)a;
  }
}

/* Reference body layer rows. */
static void tt__net_ref_body_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__net_job *job = ctx;
  float tmp[TT__NET_MAX_CH];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < job->s->width; x++) {
      tt__net_ref_conv(job->s, job->layer, job->set, job->in_plane, x, y, tmp);
      float *o = job->out_plane + tt__net_pidx(job->s, x, y) * job->s->plane_stride;
      for (uint32_t c = 0; c < job->layer->out; c++) o[c] = tmp[c] > 0.0f ? tmp[c] : 0.0f;
    }
}

/* Reference head rows (libm expf, double accumulation). */
static void tt__net_ref_head_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__net_job *job = ctx;
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t wp = s->width + 2 * TT__NET_BORDER;
  float k[50], h[8];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < s->width; x++) {
      tt__net_ref_conv(s, &m->kernel, m->kernel.sets > 1 ? job->set : 0, job->in_plane, x, y, k);
      float mx = -INFINITY;
      for (int n = 0; n < 50; n++) mx = fmaxf(mx, k[n]);
      double sum = 0.0;
      for (int n = 0; n < 50; n++) sum += (k[n] = expf(k[n] - mx));
      double o[3] = {0, 0, 0};
      size_t pi = tt__net_pidx(s, x, y);
      for (int n = 0; n < 25; n++) {
        size_t q = pi + (size_t)(n / 5) * wp + (size_t)(n % 5) - 2 * wp - 2;
        for (int c = 0; c < 3; c++)
          o[c] += (double)k[n] * s->tm[3 * q + c] + (double)k[25 + n] * s->reproj[3 * q + c];
      }
      size_t i = (size_t)y * s->width + x;
      float *st = s->next_state + i * s->state_ch;
      for (int c = 0; c < 3; c++) st[c] = (float)(o[c] / sum);
      if (m->hidden) {
        tt__net_ref_conv(s, &m->hid, m->hid.sets > 1 ? job->set : 0, job->in_plane, x, y, h);
        for (uint32_t c = 0; c < m->hidden; c++) st[3 + c] = h[c];
      }
      tt__taa_untonemap(st, job->out_rgb + 3 * i);
    }
}

void tt__net_reject_begin(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                          const tt__net_frame *f) {
  if (!(m->flags & TT__NET_FLAG_REJECT)) return;
  size_t n = (size_t)s->width * s->height;
  uint64_t t0 = host && host->clock_ns ? host->clock_ns() : 0;
  if (!s->valid) {
    /* A fresh start rejects everything (the new frame stands in for the history). */
    memset(s->reject, TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET, n);
  } else {
    tt__taa_reject_masks(host, s->width, s->height, s->have_prev_depth ? s->prev_depth : NULL,
                         s->prev_jitter, f->prev_depth, f->motion, f->jitter, s->reject,
                         s->reject + n);
  }
  s->ms_reject = host && host->clock_ns ? (double)(host->clock_ns() - t0) * 1e-6 : 0.0;
}

void tt__net_reject_end(tt__net_state *s, const tt__net_model *m, const tt__net_frame *f) {
  if (!(m->flags & TT__NET_FLAG_REJECT)) return;
  s->have_prev_depth = f->depth != NULL;
  if (f->depth) memcpy(s->prev_depth, f->depth, (size_t)s->width * s->height * sizeof(float));
  s->prev_jitter[0] = f->jitter[0];
  s->prev_jitter[1] = f->jitter[1];
}

void tt__net_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                     const float *color, const float *depth, const float *motion,
                     uint32_t jitter_index, float *out_rgb) {
  tt__net_frame f = {
      .color = color, .depth = depth, .motion = motion, .jitter_index = jitter_index};
  tt_jitter_halton23(jitter_index, f.jitter);
  tt__net_process_frame(s, m, host, &f, out_rgb);
}

void tt__net_process_frame(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                           const tt__net_frame *f, float *out_rgb) {
  if (!s->reference) {
    /* the fast path runs the rejection tests inside its reprojection pass */
    tt__net_fast_process(s, m, host, f, out_rgb);
    tt__net_reject_end(s, m, f);
    return;
  }
  tt__net_reject_begin(s, m, host, f);
  const float *color = f->color, *depth = f->depth, *motion = f->motion;
  uint32_t jitter_index = f->jitter_index;
  if (tt__net_reference_planes(s) != TT_OK) {
    memcpy(out_rgb, color, (size_t)s->width * s->height * 3 * sizeof(float));
    return;
  }
  const tt_host *h = host;
  uint64_t t0 = h && h->clock_ns ? h->clock_ns() : 0;
  double c0 = tt__taa_cpu_ms();
  tt__net_job job = {.s = s,
                     .m = m,
                     .color = color,
                     .depth = depth,
                     .motion = motion,
                     .reject = (m->flags & TT__NET_FLAG_REJECT) ? s->reject : NULL,
                     .set = jitter_index % TT__NET_JITTER_SETS,
                     .out_rgb = out_rgb};
  /* Depth enters as a fraction of the frame's farthest hit, so scenes of any scale look
   * alike to the network. */
  float dmax = 0.0f;
  if (depth)
    for (size_t i = 0; i < (size_t)s->width * s->height; i++)
      if (depth[i] > dmax && isfinite(depth[i])) dmax = depth[i];
  job.depth_scale = dmax > 0.0f ? 1.0f / dmax : 0.0f;
  tt__taa_parallel_rows(h, s->height, tt__net_input_rows, &job);
  uint64_t t1 = h && h->clock_ns ? h->clock_ns() : 0;
  double c1 = tt__taa_cpu_ms();
  int cur = 0;
  for (uint32_t l = 0; l < m->body_count; l++) {
    job.layer = &m->body[l];
    job.set = m->body[l].sets > 1 ? jitter_index % TT__NET_JITTER_SETS : 0;
    job.in_plane = s->planes[cur];
    job.out_plane = s->planes[cur ^ 1];
    tt__taa_parallel_rows(h, s->height, tt__net_ref_body_rows, &job);
    cur ^= 1;
  }
  job.set = jitter_index % TT__NET_JITTER_SETS;
  job.in_plane = s->planes[cur];
  uint64_t t2 = h && h->clock_ns ? h->clock_ns() : 0;
  double c2 = tt__taa_cpu_ms();
  tt__taa_parallel_rows(h, s->height, tt__net_ref_head_rows, &job);
  uint64_t t3 = h && h->clock_ns ? h->clock_ns() : 0;
  double c3 = tt__taa_cpu_ms();
  s->cpu_reproject = c1 - c0;
  s->cpu_network = c2 - c1;
  s->cpu_mix = c3 - c2;
  float *t = s->state;
  s->state = s->next_state;
  s->next_state = t;
  s->valid = 1;
  s->ms_reproject = (double)(t1 - t0) * 1e-6;
  s->ms_network = (double)(t2 - t1) * 1e-6;
  s->ms_mix = (double)(t3 - t2) * 1e-6;
  tt__net_reject_end(s, m, f);
}
