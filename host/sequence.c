/* host: --sequence rendering (see sequence.h). Each frame is rendered with every sample at
 * the frame's Halton(2,3) jitter (tt_render_ctx.fixed_jitter), so geometry aliases as in a
 * rasteriser while shading converges with --spp; motion vectors come from the previous
 * frame's pose (one frame interval earlier, also for the first frame). An animated scene
 * is posed at each frame's time and its accel updated (tt_session_set_time: the accel's
 * refit or rebuild) before the frame renders; the manifest records each update. The reference frame
 * is the same pose rendered at --reference-scale times the resolution per axis with
 * ordinary random sub-pixel positions, downsampled with a Blackman-Harris filter. */
#include "sequence.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define TT__SEQ_BH_RADIUS 1.0f /* output pixels: close to the 1-pixel box TAA converges to */

/* Blackman-Harris window on [-r, r] (0 outside). */
static double tt__bh(double x, double r) {
  if (fabs(x) >= r) return 0.0;
  double t = x / (2.0 * r) + 0.5;
  return 0.35875 - 0.48829 * cos(2.0 * M_PI * t) + 0.14128 * cos(4.0 * M_PI * t) -
         0.01168 * cos(6.0 * M_PI * t);
}

void tt__downsample_bh(const float *src, uint32_t scale, uint32_t w, uint32_t h, float radius,
                       float *dst) {
  uint32_t sw = w * scale, sh = h * scale;
  int reach = (int)ceilf(radius * (float)scale) + 1;
  /* Separable: horizontal pass into tmp (sh x w), then vertical. */
  float *tmp = malloc((size_t)sh * w * 3 * sizeof(float));
  if (!tmp) return;
  for (uint32_t x = 0; x < w; x++) {
    double cx = (x + 0.5) * scale; /* output centre in source pixels */
    int i0 = (int)floor(cx) - reach, i1 = (int)floor(cx) + reach;
    for (uint32_t y = 0; y < sh; y++) {
      double acc[3] = {0, 0, 0}, ws = 0;
      for (int i = i0; i <= i1; i++) {
        if (i < 0 || i >= (int)sw) continue;
        double wt = tt__bh((i + 0.5 - cx) / scale, radius);
        if (wt <= 0) continue;
        const float *p = src + ((size_t)y * sw + i) * 3;
        for (int c = 0; c < 3; c++) acc[c] += wt * p[c];
        ws += wt;
      }
      for (int c = 0; c < 3; c++) tmp[((size_t)y * w + x) * 3 + c] = (float)(acc[c] / ws);
    }
  }
  for (uint32_t y = 0; y < h; y++) {
    double cy = (y + 0.5) * scale;
    int j0 = (int)floor(cy) - reach, j1 = (int)floor(cy) + reach;
    for (uint32_t x = 0; x < w; x++) {
      double acc[3] = {0, 0, 0}, ws = 0;
      for (int j = j0; j <= j1; j++) {
        if (j < 0 || j >= (int)sh) continue;
        double wt = tt__bh((j + 0.5 - cy) / scale, radius);
        if (wt <= 0) continue;
        const float *p = tmp + ((size_t)j * w + x) * 3;
        for (int c = 0; c < 3; c++) acc[c] += wt * p[c];
        ws += wt;
      }
      for (int c = 0; c < 3; c++) dst[((size_t)y * w + x) * 3 + c] = (float)(acc[c] / ws);
    }
  }
  free(tmp);
}

/* Everything one sequence run holds besides the session. */
typedef struct tt__seq {
  const tt__host_options *opt;
  tt__session ses; /* scene, plugins, configurations, accel, integrator, film */
  const tt_post_iface *pi;
  tt_post *post;
  const char *post_name;
  uint64_t seed;
  uint32_t spp;
  char dir[4096];      /* output folder (--out-dir, or the folder of the --out pattern) */
  const char *pattern; /* file name part of the --out pattern, or NULL */
} tt__seq;

/* What a sequence writes per frame. */
typedef enum tt__seq_file {
  TT__SEQ_COLOR,
  TT__SEQ_DEPTH,
  TT__SEQ_MOTION,
  TT__SEQ_REFERENCE,
  TT__SEQ_POST,
  TT__SEQ_NORMAL,
  TT__SEQ_ALBEDO,
  TT__SEQ_PREVDEPTH
} tt__seq_file;

/* File name (inside s->dir) of frame f's `what`. --out-dir: color_0007.exr, depth_0007.exr,
 * ... With an --out pattern the frame itself takes the pattern's name -- the reference with
 * --supersample, else the post-filtered frame when a filter runs, else the rendered frame --
 * and the other files sit beside it: frame_0007.raw.exr (rendered frame under a filter),
 * frame_0007.depth.exr, frame_0007.motion.exr, frame_0007.reference.exr. */
static void tt__seq_name(const tt__seq *s, tt__seq_file what, uint32_t f, char *out, size_t n) {
  static const char *const legacy[] = {"color", "depth",  "motion", "reference",
                                       "post",  "normal", "albedo", "prevdepth"};
  if (!s->pattern) {
    snprintf(out, n, "%s_%04u.exr", legacy[what], f);
    return;
  }
  tt__seq_file main = s->opt->reference_only ? TT__SEQ_REFERENCE
                      : s->post              ? TT__SEQ_POST
                                             : TT__SEQ_COLOR;
  char name[1024];
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
  snprintf(name, sizeof name, s->pattern, (int)f); /* checked: one %d conversion */
#pragma GCC diagnostic pop
  if (what == main) {
    snprintf(out, n, "%s", name);
    return;
  }
  static const char *const suffix[] = {"raw",  "depth",  "motion", "reference",
                                       "post", "normal", "albedo", "prevdepth"};
  size_t stem = strlen(name) - 4; /* the pattern ends in .exr */
  snprintf(out, n, "%.*s.%s.exr", (int)stem, name, suffix[what]);
}

/* Config of the first loaded plugin of `kind` (or named `name`), and its interface. */
static const void *tt__seq_find(tt__seq *s, uint32_t kind, const char *name,
                                const tt_config **cfg) {
  for (size_t i = 0; i < tt_registry_count(s->ses.reg); i++) {
    tt_loaded_plugin *p = tt_registry_get(s->ses.reg, i);
    const tt_plugin *e = tt_loaded_plugin_entry(p);
    if (e->kind != kind || (name && strcmp(e->name, name))) continue;
    *cfg = s->ses.configs[i];
    return tt_loaded_plugin_iface(p);
  }
  *cfg = NULL;
  return NULL;
}

/* Renders one frame of `cam` into `film` (cleared) with all samples at `jitter` (or random
 * sub-pixel positions when jitter is NULL) and resolves it into `rgb`. */
static tt_status tt__seq_render(tt__seq *s, tt_film *film, const tt_camera *cam,
                                const tt_camera *prev, const float *jitter, uint64_t seed,
                                float *rgb) {
  tt_film_clear(film);
  const tt_integrator_iface *ii = tt_loaded_plugin_iface(s->ses.integ_p);
  ii->reset(tt_session_integrator(s->ses.lib));
  tt_render_ctx ctx;
  tt_session_init_ctx(s->ses.lib, &ctx);
  ctx.film = film;
  ctx.camera = cam;
  ctx.prev_camera = prev;
  ctx.seed = seed;
  ctx.pass_index = 0;
  ctx.sample_offset = 0;
  ctx.spp = s->spp;
  if (jitter) {
    ctx.fixed_jitter = 1;
    ctx.jitter[0] = jitter[0];
    ctx.jitter[1] = jitter[1];
  }
  tt_pass_stats ps;
  memset(&ps, 0, sizeof ps);
  ps.struct_size = sizeof ps;
  tt_status st = tt_session_render_ctx(s->ses.lib, &ctx, &ps);
  if (st == TT_OK) tt_film_resolve(film, rgb);
  return st;
}

/* Depth, in the previous frame's camera `prev`, of the point each pixel sees: the depth
 * its reprojected history should have (a post-filter compares it with the previous frame's
 * depth where the motion vector points, to detect disocclusions). From the depth AOV (view
 * depth along `cam`'s axis) and both poses: pixel (x, y)'s ray through its jittered film
 * position -- the one every sample of the frame used -- meets its surface at that depth;
 * that point is projected into `prev`. 0 for the sky (depth 0) and for points behind
 * `prev`. Exact for the fixed-jitter frames of a sequence. */
static void tt__seq_prev_depth(const tt_camera *cam, const tt_camera *prev, const float jit[2],
                               const float *depth, uint32_t w, uint32_t h, float *out) {
  tt_camera_frame cf, pf;
  if (tt_camera_frame_init(&cf, cam) != TT_OK || tt_camera_frame_init(&pf, prev) != TT_OK) {
    tt_clear_error();
    memcpy(out, depth, (size_t)w * h * sizeof(float)); /* degenerate pose: no motion */
    return;
  }
  for (uint32_t y = 0; y < h; y++)
    for (uint32_t x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      float z = depth[i], zp = 0.0f;
      if (z > 0.0f && isfinite(z)) {
        tt_ray ray;
        tt_camera_generate_ray(&cf, (float)x + 0.5f + jit[0], (float)y + 0.5f + jit[1], &ray);
        float c =
            ray.dir[0] * cf.forward[0] + ray.dir[1] * cf.forward[1] + ray.dir[2] * cf.forward[2];
        float t = z / c, p[3];
        for (int k = 0; k < 3; k++) p[k] = ray.org[k] + t * ray.dir[k];
        if (!tt_camera_project(&pf, p, NULL, NULL, &zp)) zp = 0.0f;
      }
      out[i] = zp;
    }
}

/* Writes an EXR, reporting failures. */
static int tt__seq_write(const char *path, uint32_t w, uint32_t h, uint32_t ch, const float *px,
                         const char *const *names) {
  tt_image_meta meta[] = {{"software", "tunetrace " TT_VERSION_STRING}};
  if (tt_image_write_exr(path, w, h, ch, px, names, meta, 1) != TT_OK) {
    tt__say("cannot write %s: %s\n", path, tt_last_error());
    return -1;
  }
  return 0;
}

/* The manifest so far (the memstream `m`) closed with "]}" and written atomically, after
 * every frame: a kill keeps a valid manifest listing every frame already written. */
static int tt__seq_manifest_commit(const char *path, FILE *m, char **buf, size_t *len) {
  static const char tail[] = "  ]\n}\n";
  tt_atomic_file *f = NULL;
  if (fflush(m) != 0 || tt_atomic_file_open(path, &f) != TT_OK) {
    tt__say("cannot write %s: %s\n", path, f ? "out of memory" : tt_last_error());
    return -1;
  }
  FILE *out = tt_atomic_file_stream(f);
  fwrite(*buf, 1, *len, out);
  fputs(tail, out);
  if (tt_atomic_file_commit(f) != TT_OK) {
    tt__say("cannot write %s: %s\n", path, tt_last_error());
    return -1;
  }
  return 0;
}

int tt__run_sequence(const tt__host_options *opt) {
  if (!opt->out_dir && !opt->seq_pattern) {
    tt__say("--sequence needs --out-dir DIR (or --out DIR/frame_%%04d.exr)\n");
    return TT_EXIT_USAGE;
  }
  /* SIGINT/SIGTERM: the current frame finishes and stays in the manifest (it is committed
   * after every frame); a second signal exits at once, leaving the frames committed so far */
  tt__install_signals("frame");
  tt__seq s;
  memset(&s, 0, sizeof s);
  s.opt = opt;
  if (opt->seq_pattern) {
    const char *slash = strrchr(opt->seq_pattern, '/');
    if (slash)
      snprintf(s.dir, sizeof s.dir, "%.*s",
               (int)(slash - opt->seq_pattern + (slash == opt->seq_pattern)), opt->seq_pattern);
    else snprintf(s.dir, sizeof s.dir, ".");
    s.pattern = slash ? slash + 1 : opt->seq_pattern;
  } else {
    snprintf(s.dir, sizeof s.dir, "%s", opt->out_dir);
  }
  if (tt__ensure_dir(s.dir) != 0) {
    tt__say("%s %s: cannot create the directory: %s\n", opt->seq_pattern ? "--out" : "--out-dir",
            s.dir, strerror(errno));
    return TT_EXIT_OUTPUT;
  }
  int rc = TT_EXIT_OK;
  float *rgb = NULL, *ref_hi = NULL, *ref = NULL, *post_rgb = NULL, *motion = NULL;
  tt_film *film = NULL, *ref_film = NULL;
  float *prev_depth = NULL;
  FILE *manifest = NULL; /* memstream over mbuf: the manifest text so far */
  char *mbuf = NULL, mpath[4096 + 32];
  size_t mlen = 0;
  rc = tt__session_open(&s.ses, opt);
  if (rc != TT_EXIT_OK) goto done;
  const tt_host *host = s.ses.host;
  const tt_config *pcfg = NULL;
  if (opt->post) {
    char name[128];
    const char *slash = strrchr(opt->post, '/');
    snprintf(name, sizeof name, "%s", slash ? slash + 1 : opt->post);
    char *dot = strstr(name, ".so");
    if (dot) *dot = 0;
    s.pi = tt__seq_find(&s, TT_KIND_POST, name, &pcfg);
    if (!s.pi) {
      tt__say("--post %s: not a post-filter plugin (kind post)\n", opt->post);
      rc = TT_EXIT_PLUGIN;
      goto done;
    }
    s.post_name = tt_loaded_plugin_entry(tt_registry_find_name(s.ses.reg, name))->name;
  } else {
    /* --plugin post_taa: a loaded post-filter runs over the frames as with --post */
    s.pi = tt__seq_find(&s, TT_KIND_POST, NULL, &pcfg);
    if (s.pi) {
      for (size_t i = 0; i < tt_registry_count(s.ses.reg); i++) {
        const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s.ses.reg, i));
        if (e->kind == TT_KIND_POST) {
          s.post_name = e->name;
          break;
        }
      }
      if (opt->reference_only) {
        tt__say("--supersample writes the reference frames: no post-filter "
                "(%s is loaded)\n",
                s.post_name);
        rc = TT_EXIT_USAGE;
        goto done;
      }
    }
  }
  const tt_render_settings *settings = tt_scene_settings(s.ses.scene);
  s.seed = opt->seed_set ? opt->seed : settings->seed;
  s.spp = opt->spp ? opt->spp : settings->spp;
  /* prevdepth is the host's own (from depth and the poses), not a film AOV */
  /* a still scene's prevdepth is the host's own (from depth and the poses); an animated
   * scene's comes from the film, which knows where each hit was (objects move too) */
  const int animated = tt_scene_animated(s.ses.scene);
  rc = tt__session_start(&s.ses, TT_AOV_DEPTH | TT_AOV_MOTION | (animated ? TT_AOV_PREV_DEPTH : 0) |
                                     (opt->aov_mask & ~TT__AOV_PREVDEPTH));
  if (rc != TT_EXIT_OK) goto done;
  const tt_camera *still = s.ses.camera;
  uint32_t w = still->width, h = still->height, k = opt->reference_scale;
  double fps = opt->fps > 0 ? opt->fps : 24.0;
  film = s.ses.film;
  rgb = malloc((size_t)w * h * 3 * sizeof(float));
  post_rgb = malloc((size_t)w * h * 3 * sizeof(float));
  motion = malloc((size_t)w * h * 2 * sizeof(float));
  prev_depth = malloc((size_t)w * h * sizeof(float));
  if (k) {
    ref_film = tt_film_create(w * k, h * k, 0);
    ref_hi = malloc((size_t)w * k * h * k * 3 * sizeof(float));
    ref = malloc((size_t)w * h * 3 * sizeof(float));
  }
  if (!rgb || !post_rgb || !motion || !prev_depth || (k && (!ref_film || !ref_hi || !ref))) {
    tt__say("out of memory for %ux%u frames\n", w, h);
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  if (s.pi && s.pi->create(w, h, pcfg, &s.post) != TT_OK) {
    tt__say("post-filter %s: %s\n", s.post_name, tt_last_error());
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  char path[4096 + 1100], name[1024];
  snprintf(mpath, sizeof mpath, "%s/manifest.json", s.dir);
  if (tt_file_check_writable(mpath) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    rc = TT_EXIT_OUTPUT;
    goto done;
  }
  manifest = open_memstream(&mbuf, &mlen);
  if (!manifest) {
    tt__say("cannot write %s: %s\n", mpath, strerror(errno));
    rc = TT_EXIT_OUTPUT;
    goto done;
  }
  fprintf(manifest,
          "{\n  \"version\": 1,\n  \"scene\": \"%s\",\n  \"width\": %u,\n"
          "  \"height\": %u,\n  \"fps\": %g,\n  \"spp\": %u,\n  \"seed\": %llu,\n"
          "  \"jitter_cycle\": %u,\n  \"reference_scale\": %u,\n"
          "  \"reference_filter\": \"blackman-harris radius %.1f px\",\n  \"post\": %s%s%s,\n"
          "  \"colour\": \"linear RGB\",\n  \"motion\": \"pixels, this frame -> previous\",\n"
          "  \"frames\": [\n",
          tt_scene_source(s.ses.scene), w, h, fps, s.spp, (unsigned long long)s.seed,
          TT__SEQ_JITTER_CYCLE, k, TT__SEQ_BH_RADIUS, s.post_name ? "\"" : "",
          s.post_name ? s.post_name : "null", s.post_name ? "\"" : "");
  if (!opt->quiet)
    tt__say("sequence %s: frames %u..%u at %g fps, %ux%u, %u spp%s%s -> %s\n", opt->scene,
            opt->seq_first, opt->seq_last, fps, w, h, s.spp,
            k ? (opt->reference_only ? ", reference only x" : ", reference x") : "",
            k ? (k == 2   ? "2"
                 : k == 4 ? "4"
                          : "K")
              : "",
            s.dir);
  static const char *const depth_names[] = {"Z"};
  static const char *const motion_names[] = {"X", "Y"};
  static const char *const normal_names[] = {"X", "Y", "Z"};
  static const char *const albedo_names[] = {"R", "G", "B"};
  uint32_t nframes = opt->seq_last - opt->seq_first + 1;
  /* the jittered frame is rendered unless only the reference is asked for */
  int render_frame = !opt->reference_only || opt->aov_mask;
  int entry_open = 0; /* a frame's manifest entry is started but not closed */
  uint32_t done_frames = 0;
  for (uint32_t f = opt->seq_first; f <= opt->seq_last && rc == TT_EXIT_OK; f++) {
    /* a stop asked for during the frame before (or, for the first frame, during the scene
     * loading and accel build) ends the sequence here; the first frame is always completed,
     * as a still completes its first pass: exit 130 comes with what was rendered so far */
    if (f > opt->seq_first && host->should_stop()) {
      rc = TT_EXIT_INTERRUPTED;
      break;
    }
    tt_default_host_hold_stop(1);
    tt_camera cam, prev;
    tt_scene_camera_at(s.ses.scene, f / fps, &cam);
    tt_scene_camera_at(s.ses.scene, (f - 1.0) / fps, &prev);
    cam.width = prev.width = w;
    cam.height = prev.height = h;
    uint32_t ji = f % TT__SEQ_JITTER_CYCLE;
    float jit[2];
    tt_jitter_halton23(ji, jit);
    entry_open = 1;
    fprintf(manifest,
            "    %s{\"index\": %u, \"time\": %.6f, \"jitter_index\": %u, "
            "\"jitter\": [%.6f, %.6f], \"reset\": %s",
            f == opt->seq_first ? "" : ",", f, f / fps, ji, jit[0], jit[1],
            f == opt->seq_first ? "true" : "false");
    double render_ms = 0, ref_ms = 0, post_ms = 0;
    const float *depth = NULL;
    if (animated) {
      tt_accel_update_stats us = {.struct_size = sizeof us};
      if (tt_session_set_time(s.ses.lib, f / fps, 1.0 / fps, &us) != TT_OK) {
        tt__say("frame %u: %s\n", f, tt_last_error());
        rc = TT_EXIT_FAILURE;
        break;
      }
      fprintf(manifest, ", \"update\": \"%s\", \"update_ms\": %.3f",
              us.rebuilt ? "rebuild" : "refit", us.update_ms);
      if (us.sah_cost > 0) fprintf(manifest, ", \"sah_cost\": %.4f", us.sah_cost);
    }
    if (render_frame) {
      uint64_t t0 = host->clock_ns();
      if (tt__seq_render(&s, film, &cam, &prev, jit, s.seed + f, rgb) != TT_OK) {
        tt__say("frame %u: %s\n", f, tt_last_error());
        rc = TT_EXIT_FAILURE;
        break;
      }
      render_ms = (host->clock_ns() - t0) * 1e-6;
      depth = tt_film_aov_const(film, TT_AOV_DEPTH);
      memcpy(motion, tt_film_aov_const(film, TT_AOV_MOTION), (size_t)w * h * 2 * sizeof(float));
      if (animated)
        memcpy(prev_depth, tt_film_aov_const(film, TT_AOV_PREV_DEPTH),
               (size_t)w * h * sizeof(float));
      else tt__seq_prev_depth(&cam, &prev, jit, depth, w, h, prev_depth);
      struct {
        tt__seq_file what;
        const char *key;
        int on;
        uint32_t ch;
        const float *px;
        const char *const *names;
      } files[] = {
          {TT__SEQ_COLOR, "color", !opt->reference_only, 3, rgb, NULL},
          {TT__SEQ_DEPTH, "depth", !!(opt->aov_mask & TT__AOV_DEPTH), 1, depth, depth_names},
          {TT__SEQ_MOTION, "motion", !!(opt->aov_mask & TT__AOV_MOTION), 2, motion, motion_names},
          {TT__SEQ_NORMAL, "normal", !!(opt->aov_mask & TT__AOV_NORMAL), 3,
           tt_film_aov_const(film, TT_AOV_NORMAL), normal_names},
          {TT__SEQ_ALBEDO, "albedo", !!(opt->aov_mask & TT__AOV_ALBEDO), 3,
           tt_film_aov_const(film, TT_AOV_ALBEDO), albedo_names},
          {TT__SEQ_PREVDEPTH, "prev_depth", !!(opt->aov_mask & TT__AOV_PREVDEPTH), 1, prev_depth,
           depth_names},
      };
      for (size_t i = 0; i < sizeof files / sizeof files[0] && rc == TT_EXIT_OK; i++) {
        if (!files[i].on) continue;
        tt__seq_name(&s, files[i].what, f, name, sizeof name);
        snprintf(path, sizeof path, "%s/%s", s.dir, name);
        if (tt__seq_write(path, w, h, files[i].ch, files[i].px, files[i].names))
          rc = TT_EXIT_OUTPUT;
        else fprintf(manifest, ", \"%s\": \"%s\"", files[i].key, name);
      }
      if (rc != TT_EXIT_OK) break;
    }
    if (k) {
      tt_camera hi = cam;
      hi.width = w * k;
      hi.height = h * k;
      uint64_t r0 = host->clock_ns();
      if (tt__seq_render(&s, ref_film, &hi, NULL, NULL, s.seed + 1000003u * (f + 1), ref_hi) !=
          TT_OK) {
        tt__say("reference frame %u: %s\n", f, tt_last_error());
        rc = TT_EXIT_FAILURE;
        break;
      }
      tt__downsample_bh(ref_hi, k, w, h, TT__SEQ_BH_RADIUS, ref);
      ref_ms = (host->clock_ns() - r0) * 1e-6;
      tt__seq_name(&s, TT__SEQ_REFERENCE, f, name, sizeof name);
      snprintf(path, sizeof path, "%s/%s", s.dir, name);
      if (tt__seq_write(path, w, h, 3, ref, NULL)) {
        rc = TT_EXIT_OUTPUT;
        break;
      }
      fprintf(manifest, ", \"reference\": \"%s\"", name);
    }
    if (s.post) {
      tt_post_frame pf;
      memset(&pf, 0, sizeof pf);
      pf.struct_size = sizeof pf;
      pf.width = w;
      pf.height = h;
      pf.color = rgb;
      pf.depth = depth;
      pf.motion = motion;
      pf.frame_index = f - opt->seq_first;
      pf.jitter_index = ji;
      pf.jitter[0] = jit[0];
      pf.jitter[1] = jit[1];
      pf.reset_history = f == opt->seq_first;
      pf.prev_depth = prev_depth;
      uint64_t p0 = host->clock_ns();
      if (s.pi->process(s.post, &pf, post_rgb) != TT_OK) {
        tt__say("post-filter %s: frame %u: %s\n", s.post_name, f, tt_last_error());
        rc = TT_EXIT_FAILURE;
        break;
      }
      post_ms = (host->clock_ns() - p0) * 1e-6;
      tt__seq_name(&s, TT__SEQ_POST, f, name, sizeof name);
      snprintf(path, sizeof path, "%s/%s", s.dir, name);
      if (tt__seq_write(path, w, h, 3, post_rgb, NULL)) {
        rc = TT_EXIT_OUTPUT;
        break;
      }
      fprintf(manifest, ", \"post\": \"%s\", \"post_ms\": %.3f", name, post_ms);
    }
    if (opt->png) {
      /* the frame the pattern names (tt__seq_name), through the display transform of stills */
      tt__seq_file main = opt->reference_only ? TT__SEQ_REFERENCE
                          : s.post            ? TT__SEQ_POST
                                              : TT__SEQ_COLOR;
      const float *px = main == TT__SEQ_REFERENCE ? ref : main == TT__SEQ_POST ? post_rgb : rgb;
      tt__seq_name(&s, main, f, name, sizeof name);
      size_t len = strlen(name);
      if (len > 4) memcpy(name + len - 4, ".png", 4); /* every frame name ends in .exr */
      snprintf(path, sizeof path, "%s/%s", s.dir, name);
      tt_image_meta meta[] = {{"software", "tunetrace " TT_VERSION_STRING}};
      if (tt_image_write_png_display(path, w, h, px, 0.0f, meta, 1) != TT_OK) {
        tt__say("cannot write %s: %s\n", path, tt_last_error());
        rc = TT_EXIT_OUTPUT;
        break;
      }
      fprintf(manifest, ", \"png\": \"%s\"", name);
    }
    fprintf(manifest, ", \"render_ms\": %.3f, \"reference_ms\": %.3f}\n", render_ms, ref_ms);
    entry_open = 0;
    if (tt__seq_manifest_commit(mpath, manifest, &mbuf, &mlen)) rc = TT_EXIT_OUTPUT;
    tt_default_host_hold_stop(0);
    done_frames++;
    tt__progress_update("sequence", (double)(f - opt->seq_first + 1) / nframes);
  }
  tt_default_host_hold_stop(0);
  /* a frame that failed half-way still closes its manifest entry */
  if (entry_open) fprintf(manifest, ", \"incomplete\": true}\n");
  tt__progress_finish();
  if (tt__seq_manifest_commit(mpath, manifest, &mbuf, &mlen) && rc == TT_EXIT_OK)
    rc = TT_EXIT_OUTPUT;
  fclose(manifest);
  manifest = NULL;
  if (!opt->quiet && rc == TT_EXIT_OK) tt__say("wrote %u frames to %s\n", nframes, s.dir);
  else if (rc == TT_EXIT_INTERRUPTED)
    tt__say("interrupted: %u of %u frames written to %s (manifest.json lists them)\n", done_frames,
            nframes, s.dir);
done:
  if (manifest) fclose(manifest);
  free(mbuf);
  if (s.post) s.pi->destroy(s.post);
  tt_film_destroy(ref_film);
  free(rgb);
  free(ref_hi);
  free(ref);
  free(post_rgb);
  free(motion);
  free(prev_depth);
  tt__session_close(&s.ses);
  return rc;
}
