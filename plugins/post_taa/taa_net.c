/* post_taa: the thesis' kernel-prediction TAA network (chapter 5.4, Fig. 5.2) in C.
 *
 * Per frame: tonemap the new colour, reproject the previous state [rgb, hidden] with
 * Catmull-Rom along the motion vectors, run the body convolutions (ReLU, zero padding),
 * then per pixel the 5x5 kernel layer (softmax over the 2 x 25 weights), the colour mix of
 * eq. 5.3 over the new frame and the reprojected output, and the 1x1 hidden-state layer.
 * Layers whose file record has 8 weight sets use set (jitter_index mod 8).
 *
 * Feature planes are HWC with a zero border of 2 pixels, so the convolution loops need no
 * bounds tests. The fast path vectorises over output channels with GCC vector extensions
 * (8 floats), compiled for AVX-512/AVX2 and a generic fallback via target_clones; the
 * reference path is plain scalar loops over the file's PyTorch layout, used by the tests
 * to check the fast one. The weights file format is documented in README.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "taa_internal.h"

typedef float v8f __attribute__((vector_size(32)));

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#  define TAA_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#  define TAA_CLONES
#endif

/* ---- weights file ---- */

/* Reads a little-endian u32 (the format is LE whatever the host). */
static uint32_t net_u32(const unsigned char *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Reads a little-endian IEEE float. */
static float net_f32(const unsigned char *p) {
  uint32_t u = net_u32(p);
  float f;
  memcpy(&f, &u, 4);
  return f;
}

/* FNV-1a 32-bit over the payload: cheap and catches torn or edited files. */
static uint32_t net_fnv1a(const unsigned char *p, size_t n) {
  uint32_t h = 2166136261u;
  for (size_t i = 0; i < n; i++) {
    h ^= p[i];
    h *= 16777619u;
  }
  return h;
}

/* 32-byte aligned zeroed floats (the SIMD loops load weights as aligned vectors). */
static float *net_alloc(size_t count) {
  size_t bytes = (count * sizeof(float) + 31) & ~(size_t)31;
  float *p = aligned_alloc(32, bytes ? bytes : 32);
  if (p) memset(p, 0, bytes ? bytes : 32);
  return p;
}

/* Frees one layer's arrays. */
static void net_layer_free(tt__net_layer *l) {
  free(l->w);
  free(l->b);
  free(l->wp);
  free(l->bp);
  memset(l, 0, sizeof *l);
}

void tt__net_free(tt__net_model *m) {
  for (uint32_t i = 0; i < TT__NET_MAX_LAYERS; i++) net_layer_free(&m->body[i]);
  net_layer_free(&m->kernel);
  net_layer_free(&m->hid);
}

/* Copies weights from the payload and repacks them for the SIMD loops. */
static tt_status net_layer_read(tt__net_layer *l, const unsigned char *p, const char *src) {
  size_t per = (size_t)l->out * l->in * l->ksize * l->ksize;
  size_t kk = (size_t)l->ksize * l->ksize;
  l->out_pad = (l->out + 7u) & ~7u;
  l->w = net_alloc(per * l->sets);
  l->b = net_alloc((size_t)l->out * l->sets);
  l->wp = net_alloc(kk * l->in * l->out_pad * l->sets);
  l->bp = net_alloc((size_t)l->out_pad * l->sets);
  if (!l->w || !l->b || !l->wp || !l->bp)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory for weights", src);
  for (size_t i = 0; i < per * l->sets; i++) l->w[i] = net_f32(p + 4 * i);
  p += 4 * per * l->sets;
  for (size_t i = 0; i < (size_t)l->out * l->sets; i++) l->b[i] = net_f32(p + 4 * i);
  for (uint32_t s = 0; s < l->sets; s++) {
    for (uint32_t o = 0; o < l->out; o++) {
      l->bp[s * l->out_pad + o] = l->b[s * l->out + o];
      for (uint32_t c = 0; c < l->in; c++)
        for (size_t t = 0; t < kk; t++)
          l->wp[((s * kk + t) * l->in + c) * l->out_pad + o] =
              l->w[s * per + ((size_t)o * l->in + c) * kk + t];
    }
  }
  return TT_OK;
}

#define NET_HEADER_FIXED 48u  /* magic 8, version, header size, 6 counts, motion scale, 2 reserved */
#define NET_LAYER_RECORD 24u  /* role, in, out, ksize, sets, activation */

tt_status tt__net_parse(const void *data, size_t size, const char *src, tt__net_model *m) {
  const unsigned char *p = data;
  memset(m, 0, sizeof *m);
  if (size < 12 || memcmp(p, TT__NET_MAGIC, 8) != 0)
    return tt_set_error(TT_ERR_PARSE,
                        "%s: not a post_taa weights file (bad magic; expected \"TTAANET\")",
                        src);
  uint32_t version = net_u32(p + 8);
  if (version != TT__NET_VERSION)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: weights format version %u is not supported (this build reads "
                        "version %u)", src, version, TT__NET_VERSION);
  if (size < NET_HEADER_FIXED)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated header (%zu bytes, expected at least %u)",
                        src, size, NET_HEADER_FIXED);
  uint32_t header_bytes = net_u32(p + 12);
  m->in_channels = net_u32(p + 16);
  m->width = net_u32(p + 20);
  m->hidden = net_u32(p + 24);
  uint32_t mix_k = net_u32(p + 28), jitter_sets = net_u32(p + 32);
  uint32_t layers = net_u32(p + 36);
  m->motion_scale = net_f32(p + 40);
  if (mix_k != TT__NET_MIX_K || jitter_sets != TT__NET_JITTER_SETS)
    return tt_set_error(TT_ERR_PARSE, "%s: colour-mix kernel %u and jitter sets %u (expected "
                        "%u and %u)", src, mix_k, jitter_sets, TT__NET_MIX_K,
                        TT__NET_JITTER_SETS);
  if (m->hidden > 8 || m->in_channels != 9 + m->hidden || m->width < 1 ||
      m->width > TT__NET_MAX_CH || !isfinite(m->motion_scale))
    return tt_set_error(TT_ERR_PARSE, "%s: bad model shape: in %u, width %u, hidden %u "
                        "(in must be 9 + hidden, hidden <= 8, width in [1, %u])", src,
                        m->in_channels, m->width, m->hidden, TT__NET_MAX_CH);
  uint32_t want_layers_min = 2 + (m->hidden ? 1 : 0);
  if (layers < want_layers_min || layers > TT__NET_MAX_LAYERS)
    return tt_set_error(TT_ERR_PARSE, "%s: %u layers (expected %u to %u)", src, layers,
                        want_layers_min, TT__NET_MAX_LAYERS);
  if (header_bytes != NET_HEADER_FIXED + layers * NET_LAYER_RECORD)
    return tt_set_error(TT_ERR_PARSE, "%s: header size %u does not match %u layers", src,
                        header_bytes, layers);
  if (size < header_bytes)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated layer table (%zu bytes, expected %u)",
                        src, size, header_bytes);
  /* Validate every record and the chain of shapes before reading any payload. */
  size_t payload = 0;
  uint32_t prev_out = m->in_channels;
  int seen_kernel = 0, seen_hidden = 0;
  tt__net_layer recs[TT__NET_MAX_LAYERS];
  uint32_t roles[TT__NET_MAX_LAYERS];
  for (uint32_t i = 0; i < layers; i++) {
    const unsigned char *r = p + NET_HEADER_FIXED + i * NET_LAYER_RECORD;
    tt__net_layer *l = &recs[i];
    memset(l, 0, sizeof *l);
    roles[i] = net_u32(r);
    l->in = net_u32(r + 4);
    l->out = net_u32(r + 8);
    l->ksize = net_u32(r + 12);
    l->sets = net_u32(r + 16);
    l->activation = net_u32(r + 20);
    const char *what = roles[i] == 1 ? "body" : roles[i] == 2 ? "kernel" : "hidden";
    if (roles[i] < 1 || roles[i] > 3)
      return tt_set_error(TT_ERR_PARSE, "%s: layer %u: unknown role %u", src, i, roles[i]);
    if ((l->sets != 1 && l->sets != TT__NET_JITTER_SETS) || l->ksize % 2 == 0 ||
        l->ksize > 2 * TT__NET_BORDER + 1 || l->out == 0 || l->out > TT__NET_MAX_CH)
      return tt_set_error(TT_ERR_PARSE, "%s: layer %u (%s): sets %u, kernel %u, out %u "
                          "(sets 1 or 8, odd kernel <= 5, out <= %u)", src, i, what, l->sets,
                          l->ksize, l->out, TT__NET_MAX_CH);
    if (roles[i] == 1) {
      if (seen_kernel || seen_hidden || l->in != prev_out || l->out != m->width ||
          l->activation != 1)
        return tt_set_error(TT_ERR_PARSE, "%s: layer %u (body): %u -> %u, activation %u "
                            "(expected %u -> %u ReLU, before the kernel layer)", src, i,
                            l->in, l->out, l->activation, prev_out, m->width);
      prev_out = l->out;
      m->body_count++;
    } else if (roles[i] == 2) {
      if (seen_kernel || l->in != m->width || l->out != 2 * TT__NET_MIX_TAPS ||
          l->activation != 2 || m->body_count == 0)
        return tt_set_error(TT_ERR_PARSE, "%s: layer %u (kernel): %u -> %u, activation %u "
                            "(expected %u -> %u softmax after the body)", src, i, l->in,
                            l->out, l->activation, m->width, 2 * TT__NET_MIX_TAPS);
      seen_kernel = 1;
    } else {
      if (seen_hidden || l->in != m->width || l->out != m->hidden || l->ksize != 1 ||
          l->activation != 0 || m->hidden == 0 || m->body_count == 0)
        return tt_set_error(TT_ERR_PARSE, "%s: layer %u (hidden): %u -> %u, kernel %u "
                            "(expected %u -> %u, 1x1, no activation)", src, i, l->in, l->out,
                            l->ksize, m->width, m->hidden);
      seen_hidden = 1;
    }
    payload += 4 * ((size_t)l->sets * l->out * (l->in * l->ksize * l->ksize + 1));
  }
  if (!seen_kernel || (m->hidden && !seen_hidden))
    return tt_set_error(TT_ERR_PARSE, "%s: missing %s layer", src,
                        !seen_kernel ? "kernel" : "hidden");
  size_t want = header_bytes + payload + 4;
  if (size < want)
    return tt_set_error(TT_ERR_PARSE, "%s: truncated: %zu bytes, the layer table needs %zu",
                        src, size, want);
  if (size > want)
    return tt_set_error(TT_ERR_PARSE, "%s: %zu trailing bytes after the checksum", src,
                        size - want);
  uint32_t sum = net_fnv1a(p + header_bytes, payload);
  if (sum != net_u32(p + header_bytes + payload))
    return tt_set_error(TT_ERR_PARSE, "%s: checksum mismatch (file corrupted)", src);
  const unsigned char *q = p + header_bytes;
  uint32_t b = 0;
  for (uint32_t i = 0; i < layers; i++) {
    tt__net_layer *dst = roles[i] == 1 ? &m->body[b++] : roles[i] == 2 ? &m->kernel : &m->hid;
    *dst = recs[i];
    tt_status st = net_layer_read(dst, q, src);
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
  FILE *f = fopen(path, "rb");
  if (!f) return tt_set_error(TT_ERR_IO, "%s: cannot open the weights file", path);
  if (fseek(f, 0, SEEK_END) != 0) {
    fclose(f);
    return tt_set_error(TT_ERR_IO, "%s: cannot read the weights file", path);
  }
  long n = ftell(f);
  rewind(f);
  unsigned char *buf = n > 0 ? malloc((size_t)n) : NULL;
  if (n <= 0 || !buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
    free(buf);
    fclose(f);
    return tt_set_error(n == 0 ? TT_ERR_PARSE : TT_ERR_IO, "%s: %s", path,
                        n == 0 ? "empty weights file" : "cannot read the weights file");
  }
  fclose(f);
  tt_status st = tt__net_parse(buf, (size_t)n, path, m);
  free(buf);
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
  size_t ppx = (size_t)(width + 2 * TT__NET_BORDER) * (height + 2 * TT__NET_BORDER);
  s->state = net_alloc(px * s->state_ch);
  s->next_state = net_alloc(px * s->state_ch);
  s->planes[0] = net_alloc(ppx * ch + 8);
  s->planes[1] = net_alloc(ppx * ch + 8);
  s->tm = net_alloc(ppx * 3);
  s->reproj = net_alloc(ppx * 3);
  if (!s->state || !s->next_state || !s->planes[0] || !s->planes[1] || !s->tm || !s->reproj) {
    tt__net_state_free(s);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for %ux%u "
                        "network planes", width, height);
  }
  return TT_OK;
}

void tt__net_state_free(tt__net_state *s) {
  free(s->state);
  free(s->next_state);
  free(s->planes[0]);
  free(s->planes[1]);
  free(s->tm);
  free(s->reproj);
  memset(s, 0, sizeof *s);
}

/* ---- per-frame passes ---- */

typedef struct net_job {
  tt__net_state *s;
  const tt__net_model *m;
  const float *color, *depth, *motion;
  float depth_scale;
  uint32_t set;
  const tt__net_layer *layer;
  const float *in_plane;
  float *out_plane;
  float *out_rgb;
} net_job;

/* Padded plane index of pixel (x, y). */
static inline size_t net_pidx(const tt__net_state *s, uint32_t x, uint32_t y) {
  return (size_t)(y + TT__NET_BORDER) * (s->width + 2 * TT__NET_BORDER) + x + TT__NET_BORDER;
}

/* Builds the network input (plane 0), the tonemapped colour and the reprojected RGB. */
static void net_input_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const net_job *job = ctx;
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t w = s->width, sc = s->state_ch;
  float fb[16];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x, pi = net_pidx(s, x, y);
      float *in = s->planes[0] + pi * s->plane_stride;
      float t[3];
      tt__taa_tonemap(job->color + 3 * i, t);
      memcpy(s->tm + 3 * pi, t, sizeof t);
      float mx = job->motion ? job->motion[2 * i] : 0.0f;
      float my = job->motion ? job->motion[2 * i + 1] : 0.0f;
      if (s->valid) {
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
      memcpy(s->reproj + 3 * pi, fb, 3 * sizeof(float));
    }
}

/* One output pixel of a convolution: acc[0..NV*8) = bias + sum over taps and inputs. `in`
 * points at the top-left tap; `w` at the packed weights [k][k][in][out_pad]. The partial
 * sums live in a local array indexed only by unrolled constants, so they stay in registers
 * and are stored once at the end. */
static inline __attribute__((always_inline)) void net_conv_px(
    const float *in, size_t row, size_t px, uint32_t I, uint32_t K, const float *w,
    const float *b, const int NV, v8f *acc) {
  v8f r[8];
#pragma GCC unroll 8
  for (int j = 0; j < NV; j++) r[j] = *(const v8f *)(b + 8 * j);
  for (uint32_t ky = 0; ky < K; ky++)
    for (uint32_t kx = 0; kx < K; kx++) {
      const float *p = in + ky * row + kx * px;
      for (uint32_t c = 0; c < I; c++) {
        float v = p[c];
#pragma GCC unroll 8
        for (int j = 0; j < NV; j++) r[j] += v * *(const v8f *)(w + 8 * j);
        w += 8 * NV;
      }
    }
#pragma GCC unroll 8
  for (int j = 0; j < NV; j++) acc[j] = r[j];
}

/* Two horizontally adjacent output pixels at once: each weight vector loaded serves two
 * FMAs, halving the load traffic that bounds the single-pixel loop. */
static inline __attribute__((always_inline)) void net_conv_px2(
    const float *in, size_t row, size_t px, uint32_t I, uint32_t K, const float *w,
    const float *b, const int NV, v8f *acc0, v8f *acc1) {
  v8f r0[8], r1[8];
#pragma GCC unroll 8
  for (int j = 0; j < NV; j++) r0[j] = r1[j] = *(const v8f *)(b + 8 * j);
  for (uint32_t ky = 0; ky < K; ky++)
    for (uint32_t kx = 0; kx < K; kx++) {
      const float *p = in + ky * row + kx * px;
      for (uint32_t c = 0; c < I; c++) {
        float v0 = p[c], v1 = p[c + px];
#pragma GCC unroll 8
        for (int j = 0; j < NV; j++) {
          v8f wv = *(const v8f *)(w + 8 * j);
          r0[j] += v0 * wv;
          r1[j] += v1 * wv;
        }
        w += 8 * NV;
      }
    }
#pragma GCC unroll 8
  for (int j = 0; j < NV; j++) {
    acc0[j] = r0[j];
    acc1[j] = r1[j];
  }
}

/* Body layer rows with NV output vectors (constant-folded per call site). */
static inline __attribute__((always_inline)) void net_body_rows_nv(const net_job *job,
                                                                   uint32_t y0, uint32_t y1,
                                                                   const int NV) {
  const tt__net_state *s = job->s;
  const tt__net_layer *l = job->layer;
  uint32_t r = l->ksize / 2, kk = l->ksize * l->ksize;
  size_t px = s->plane_stride, row = (size_t)(s->width + 2 * TT__NET_BORDER) * px;
  const float *w = l->wp + (size_t)job->set * kk * l->in * l->out_pad;
  const float *b = l->bp + (size_t)job->set * l->out_pad;
  v8f acc[8], acc1[8];
  float tmp[64];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < s->width; x += 2) {
      size_t pi = net_pidx(s, x, y);
      const float *in = job->in_plane + (pi - r * (s->width + 2 * TT__NET_BORDER) - r) * px;
      int pair = x + 1 < s->width;
      if (pair)
        net_conv_px2(in, row, px, l->in, l->ksize, w, b, NV, acc, acc1);
      else
        net_conv_px(in, row, px, l->in, l->ksize, w, b, NV, acc);
      float *o = job->out_plane + pi * px;
      for (int j = 0; j < NV; j++) memcpy(tmp + 8 * j, &acc[j], sizeof(v8f));
      for (uint32_t c = 0; c < l->out; c++) o[c] = tmp[c] > 0.0f ? tmp[c] : 0.0f;
      if (!pair) continue;
      for (int j = 0; j < NV; j++) memcpy(tmp + 8 * j, &acc1[j], sizeof(v8f));
      for (uint32_t c = 0; c < l->out; c++) o[px + c] = tmp[c] > 0.0f ? tmp[c] : 0.0f;
    }
}

/* Body layer rows, dispatching on the padded output width. */
TAA_CLONES static void net_body_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const net_job *job = ctx;
  switch (job->layer->out_pad / 8) {
    case 1: net_body_rows_nv(job, y0, y1, 1); break;
    case 2: net_body_rows_nv(job, y0, y1, 2); break;
    case 3: net_body_rows_nv(job, y0, y1, 3); break;
    case 4: net_body_rows_nv(job, y0, y1, 4); break;
    case 5: net_body_rows_nv(job, y0, y1, 5); break;
    case 6: net_body_rows_nv(job, y0, y1, 6); break;
    case 7: net_body_rows_nv(job, y0, y1, 7); break;
    default: net_body_rows_nv(job, y0, y1, 8); break;
  }
}

/* exp(x) for x <= 0 on 8 lanes: 2^n * p(r) with a degree-6 polynomial (rel. error ~2e-7);
 * libm's scalar expf would cost more than the whole kernel layer. */
static inline __attribute__((always_inline)) void net_exp_neg(v8f *xp) {
  v8f x = *xp;
  typedef int32_t v8i __attribute__((vector_size(32)));
  const v8f lo = {-87.0f, -87.0f, -87.0f, -87.0f, -87.0f, -87.0f, -87.0f, -87.0f};
  v8i keep = x > lo;   /* lanes: -1 true, 0 false */
  v8i xi, li;
  memcpy(&xi, &x, sizeof xi);
  memcpy(&li, &lo, sizeof li);
  xi = (xi & keep) | (li & ~keep);
  memcpy(&x, &xi, sizeof x);
  /* Round to nearest with the 1.5 * 2^23 trick (exact for |t| < 2^22). */
  v8f t = x * 1.44269504088896341f;
  v8f n = (t + 12582912.0f) - 12582912.0f;
  v8f r = x - n * 0.693145751953125f - n * 1.428606765330187045e-06f;
  v8f p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  v8i e = (__builtin_convertvector(n, v8i) + 127) << 23;
  v8f scale;
  memcpy(&scale, &e, sizeof scale);
  *xp = p * scale;
}

/* Everything of the head after the kernel layer's logits `acc`, for pixel (x, y):
 * softmax, colour mix (eq. 5.3), hidden layer, state and linear output. */
static inline __attribute__((always_inline)) void net_head_finish(const net_job *job,
                                                                  uint32_t x, uint32_t y,
                                                                  v8f *acc, const float *hw,
                                                                  const float *hb) {
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t wp = s->width + 2 * TT__NET_BORDER, sc = s->state_ch;
  size_t px = s->plane_stride, row = (size_t)wp * px, pi = net_pidx(s, x, y);
  /* Softmax over the 50 logits: the padded lanes 50..55 must not count. */
  float mx = -INFINITY;
  for (int j = 0; j < 7; j++)
    for (int l = 0; l < 8 && 8 * j + l < 50; l++) mx = fmaxf(mx, acc[j][l]);
  v8f sum = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int j = 0; j < 7; j++) {
    acc[j] -= mx;
    net_exp_neg(&acc[j]);
    if (j == 6)
      for (int l = 2; l < 8; l++) acc[j][l] = 0.0f;
    sum += acc[j];
  }
  float total = 0.0f;
  for (int l = 0; l < 8; l++) total += sum[l];
  float k[56];
  float inv = 1.0f / total;
  for (int j = 0; j < 7; j++) memcpy(k + 8 * j, &acc[j], sizeof(v8f));
  /* Eq. 5.3: 25 taps over the new frame, 25 over the reprojected previous output. */
  float o[3] = {0, 0, 0};
  for (uint32_t ty = 0; ty < 5; ty++)
    for (uint32_t tx = 0; tx < 5; tx++) {
      size_t q = pi + (size_t)ty * wp + tx - 2 * wp - 2;
      float a = k[ty * 5 + tx], bb = k[25 + ty * 5 + tx];
      const float *c = s->tm + 3 * q, *r = s->reproj + 3 * q;
      o[0] += a * c[0] + bb * r[0];
      o[1] += a * c[1] + bb * r[1];
      o[2] += a * c[2] + bb * r[2];
    }
  size_t i = (size_t)y * s->width + x;
  float *st = s->next_state + i * sc;
  for (int c = 0; c < 3; c++) st[c] = o[c] * inv;
  if (m->hidden) {
    v8f hacc[1];
    net_conv_px(job->in_plane + pi * px, row, px, m->hid.in, 1, hw, hb, 1, hacc);
    for (uint32_t c = 0; c < m->hidden; c++) st[3 + c] = hacc[0][c];
  }
  tt__taa_untonemap(st, job->out_rgb + 3 * i);
}

/* Kernel layer + softmax + colour mix + hidden layer, fused per pixel (the 50 logits never
 * leave registers); pixels go in pairs through the kernel layer. */
TAA_CLONES static void net_head_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const net_job *job = ctx;
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel, *hl = &m->hid;
  uint32_t wp = s->width + 2 * TT__NET_BORDER;
  size_t px = s->plane_stride, row = (size_t)wp * px;
  uint32_t ks = kl->sets > 1 ? job->set : 0;
  uint32_t kr = kl->ksize / 2;
  const float *kw = kl->wp + (size_t)ks * kl->ksize * kl->ksize * kl->in * kl->out_pad;
  const float *kb = kl->bp + (size_t)ks * kl->out_pad;
  uint32_t hs = hl->sets > 1 ? job->set : 0;
  const float *hw = m->hidden ? hl->wp + (size_t)hs * hl->in * hl->out_pad : NULL;
  const float *hb = m->hidden ? hl->bp + (size_t)hs * hl->out_pad : NULL;
  v8f acc0[7], acc1[7];
  for (uint32_t y = y0; y < y1; y++) {
    uint32_t x = 0;
    for (; x + 1 < s->width; x += 2) {
      const float *in = job->in_plane + (net_pidx(s, x, y) - kr * wp - kr) * px;
      net_conv_px2(in, row, px, kl->in, kl->ksize, kw, kb, 7, acc0, acc1);
      net_head_finish(job, x, y, acc0, hw, hb);
      net_head_finish(job, x + 1, y, acc1, hw, hb);
    }
    if (x < s->width) {
      const float *in = job->in_plane + (net_pidx(s, x, y) - kr * wp - kr) * px;
      net_conv_px(in, row, px, kl->in, kl->ksize, kw, kb, 7, acc0);
      net_head_finish(job, x, y, acc0, hw, hb);
    }
  }
}

/* Plain scalar reference of one convolution on padded planes (file layout, no packing). */
static void net_ref_conv(const tt__net_state *s, const tt__net_layer *l, uint32_t set,
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
static void net_ref_body_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const net_job *job = ctx;
  float tmp[TT__NET_MAX_CH];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < job->s->width; x++) {
      net_ref_conv(job->s, job->layer, job->set, job->in_plane, x, y, tmp);
      float *o = job->out_plane + net_pidx(job->s, x, y) * job->s->plane_stride;
      for (uint32_t c = 0; c < job->layer->out; c++) o[c] = tmp[c] > 0.0f ? tmp[c] : 0.0f;
    }
}

/* Reference head rows (libm expf, double accumulation). */
static void net_ref_head_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const net_job *job = ctx;
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t wp = s->width + 2 * TT__NET_BORDER;
  float k[50], h[8];
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < s->width; x++) {
      net_ref_conv(s, &m->kernel, m->kernel.sets > 1 ? job->set : 0, job->in_plane, x, y, k);
      float mx = -INFINITY;
      for (int n = 0; n < 50; n++) mx = fmaxf(mx, k[n]);
      double sum = 0.0;
      for (int n = 0; n < 50; n++) sum += (k[n] = expf(k[n] - mx));
      double o[3] = {0, 0, 0};
      size_t pi = net_pidx(s, x, y);
      for (int n = 0; n < 25; n++) {
        size_t q = pi + (size_t)(n / 5) * wp + (size_t)(n % 5) - 2 * wp - 2;
        for (int c = 0; c < 3; c++)
          o[c] += (double)k[n] * s->tm[3 * q + c] + (double)k[25 + n] * s->reproj[3 * q + c];
      }
      size_t i = (size_t)y * s->width + x;
      float *st = s->next_state + i * s->state_ch;
      for (int c = 0; c < 3; c++) st[c] = (float)(o[c] / sum);
      if (m->hidden) {
        net_ref_conv(s, &m->hid, m->hid.sets > 1 ? job->set : 0, job->in_plane, x, y, h);
        for (uint32_t c = 0; c < m->hidden; c++) st[3 + c] = h[c];
      }
      tt__taa_untonemap(st, job->out_rgb + 3 * i);
    }
}

/* Process CPU time in ms (all threads): timings that survive a loaded machine. */
static double net_cpu_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

void tt__net_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                     const float *color, const float *depth, const float *motion,
                     uint32_t jitter_index, float *out_rgb) {
  const tt_host *h = host;
  uint64_t t0 = h && h->clock_ns ? h->clock_ns() : 0;
  double c0 = net_cpu_ms();
  net_job job = {.s = s, .m = m, .color = color, .depth = depth, .motion = motion,
                 .set = jitter_index % TT__NET_JITTER_SETS, .out_rgb = out_rgb};
  /* Depth enters as a fraction of the frame's farthest hit, so scenes of any scale look
   * alike to the network. */
  float dmax = 0.0f;
  if (depth)
    for (size_t i = 0; i < (size_t)s->width * s->height; i++)
      if (depth[i] > dmax && isfinite(depth[i])) dmax = depth[i];
  job.depth_scale = dmax > 0.0f ? 1.0f / dmax : 0.0f;
  tt__taa_parallel_rows(h, s->height, net_input_rows, &job);
  uint64_t t1 = h && h->clock_ns ? h->clock_ns() : 0;
  double c1 = net_cpu_ms();
  int cur = 0;
  for (uint32_t l = 0; l < m->body_count; l++) {
    job.layer = &m->body[l];
    job.set = m->body[l].sets > 1 ? jitter_index % TT__NET_JITTER_SETS : 0;
    job.in_plane = s->planes[cur];
    job.out_plane = s->planes[cur ^ 1];
    tt__taa_parallel_rows(h, s->height, s->reference ? net_ref_body_rows : net_body_rows,
                          &job);
    cur ^= 1;
  }
  job.set = jitter_index % TT__NET_JITTER_SETS;
  job.in_plane = s->planes[cur];
  uint64_t t2 = h && h->clock_ns ? h->clock_ns() : 0;
  double c2 = net_cpu_ms();
  tt__taa_parallel_rows(h, s->height, s->reference ? net_ref_head_rows : net_head_rows, &job);
  uint64_t t3 = h && h->clock_ns ? h->clock_ns() : 0;
  double c3 = net_cpu_ms();
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
}
