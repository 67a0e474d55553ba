/* host: --sequence rendering (see sequence.h). Each frame is rendered with every sample at
 * the frame's Halton(2,3) jitter (tt_render_ctx.fixed_jitter), so geometry aliases as in a
 * rasteriser while shading converges with --spp; motion vectors come from the previous
 * frame's pose (one frame interval earlier, also for the first frame). An animated scene
 * is posed at each frame's time and its accel updated (tt_session_set_time: the accel's
 * refit or rebuild) before the frame renders; the manifest records each update. The reference frame
 * is the same pose rendered at --reference-scale times the resolution per axis with
 * ordinary random sub-pixel positions, downsampled with a Blackman-Harris filter. */
#include "sequence_internal.h"

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

/* The file the --out pattern names per frame: the reference with --supersample, else the
 * post-filtered frame when a filter runs, else the rendered frame. */
static tt__seq_file tt__seq_main_file(const tt__seq *s) {
  return s->opt->reference_only ? TT__SEQ_REFERENCE : s->post ? TT__SEQ_POST : TT__SEQ_COLOR;
}

/* File name (inside s->dir) of frame f's `what`. --out-dir: color_0007.exr, depth_0007.exr,
 * ... With an --out pattern the frame itself takes the pattern's name (tt__seq_main_file)
 * and the other files sit beside it: frame_0007.raw.exr (rendered frame under a filter),
 * frame_0007.depth.exr, frame_0007.motion.exr, frame_0007.reference.exr. */
static void tt__seq_name(const tt__seq *s, tt__seq_file what, uint32_t f, char *out, size_t n) {
  static const char *const legacy[] = {"color", "depth",  "motion", "reference",
                                       "post",  "normal", "albedo", "prevdepth"};
  if (!s->pattern) {
    snprintf(out, n, "%s_%04u.exr", legacy[what], f);
    return;
  }
  char name[1024];
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
  snprintf(name, sizeof name, s->pattern, (int)f); /* checked: one %d conversion */
#pragma GCC diagnostic pop
  if (what == tt__seq_main_file(s)) {
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

/* The output folder: --out-dir, or the folder of the --out pattern (whose file name part
 * names the frames), created when missing. An exit code. */
static int tt__seq_dirs(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  if (opt->seq_pattern) {
    const char *slash = strrchr(opt->seq_pattern, '/');
    if (slash)
      snprintf(s->dir, sizeof s->dir, "%.*s",
               (int)(slash - opt->seq_pattern + (slash == opt->seq_pattern)), opt->seq_pattern);
    else snprintf(s->dir, sizeof s->dir, ".");
    s->pattern = slash ? slash + 1 : opt->seq_pattern;
  } else {
    snprintf(s->dir, sizeof s->dir, "%s", opt->out_dir);
  }
  if (tt__ensure_dir(s->dir) != 0) {
    tt__say("%s %s: cannot create the directory: %s\n", opt->seq_pattern ? "--out" : "--out-dir",
            s->dir, strerror(errno));
    return TT_EXIT_OUTPUT;
  }
  return TT_EXIT_OK;
}

/* The post-filter: --post NAME, else a post-filter loaded with --plugin (which runs over the
 * frames as with --post; not with --supersample, which writes only the references). */
static int tt__seq_pick_post(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  if (opt->post) {
    char name[128];
    const char *slash = strrchr(opt->post, '/');
    snprintf(name, sizeof name, "%s", slash ? slash + 1 : opt->post);
    char *dot = strstr(name, ".so");
    if (dot) *dot = 0;
    s->pi = tt__seq_find(s, TT_KIND_POST, name, &s->pcfg);
    if (!s->pi) {
      tt__say("--post %s: not a post-filter plugin (kind post)\n", opt->post);
      return TT_EXIT_PLUGIN;
    }
    s->post_name = tt_loaded_plugin_entry(tt_registry_find_name(s->ses.reg, name))->name;
    return TT_EXIT_OK;
  }
  s->pi = tt__seq_find(s, TT_KIND_POST, NULL, &s->pcfg);
  if (!s->pi) return TT_EXIT_OK;
  for (size_t i = 0; i < tt_registry_count(s->ses.reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->ses.reg, i));
    if (e->kind == TT_KIND_POST) {
      s->post_name = e->name;
      break;
    }
  }
  if (opt->reference_only) {
    tt__say("--supersample writes the reference frames: no post-filter (%s is loaded)\n",
            s->post_name);
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* The frame buffers (the reference's with --reference-scale) and the post-filter's state. */
static int tt__seq_buffers(tt__seq *s) {
  size_t px = (size_t)s->w * s->h;
  uint32_t k = s->k;
  s->rgb = malloc(px * 3 * sizeof(float));
  s->post_rgb = malloc(px * 3 * sizeof(float));
  s->motion = malloc(px * 2 * sizeof(float));
  s->prev_depth = malloc(px * sizeof(float));
  if (k) {
    s->ref_film = tt_film_create(s->w * k, s->h * k, 0);
    s->ref_hi = malloc(px * k * k * 3 * sizeof(float));
    s->ref = malloc(px * 3 * sizeof(float));
  }
  if (!s->rgb || !s->post_rgb || !s->motion || !s->prev_depth ||
      (k && (!s->ref_film || !s->ref_hi || !s->ref))) {
    tt__say("out of memory for %ux%u frames\n", s->w, s->h);
    return TT_EXIT_FAILURE;
  }
  if (s->pi && s->pi->create(s->w, s->h, s->pcfg, &s->post) != TT_OK) {
    tt__say("post-filter %s: %s\n", s->post_name, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  return TT_EXIT_OK;
}

/* The manifest: checked writable, its header written into the memstream (the frames follow,
 * the whole committed after each frame). */
static int tt__seq_manifest_open(tt__seq *s) {
  snprintf(s->mpath, sizeof s->mpath, "%s/manifest.json", s->dir);
  if (tt_file_check_writable(s->mpath) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_OUTPUT;
  }
  s->manifest = open_memstream(&s->mbuf, &s->mlen);
  if (!s->manifest) {
    tt__say("cannot write %s: %s\n", s->mpath, strerror(errno));
    return TT_EXIT_OUTPUT;
  }
  fprintf(s->manifest,
          "{\n  \"version\": 1,\n  \"scene\": \"%s\",\n  \"width\": %u,\n"
          "  \"height\": %u,\n  \"fps\": %g,\n  \"spp\": %u,\n  \"seed\": %llu,\n"
          "  \"jitter_cycle\": %u,\n  \"reference_scale\": %u,\n"
          "  \"reference_filter\": \"blackman-harris radius %.1f px\",\n  \"post\": %s%s%s,\n"
          "  \"colour\": \"linear RGB\",\n  \"motion\": \"pixels, this frame -> previous\",\n"
          "  \"frames\": [\n",
          tt_scene_source(s->ses.scene), s->w, s->h, s->fps, s->spp, (unsigned long long)s->seed,
          TT__SEQ_JITTER_CYCLE, s->k, TT__SEQ_BH_RADIUS, s->post_name ? "\"" : "",
          s->post_name ? s->post_name : "null", s->post_name ? "\"" : "");
  return TT_EXIT_OK;
}

/* Logs what the sequence renders (unless --quiet). */
static void tt__seq_log_start(const tt__seq *s) {
  const tt__host_options *opt = s->opt;
  if (opt->quiet) return;
  uint32_t k = s->k;
  tt__say("sequence %s: frames %u..%u at %g fps, %ux%u, %u spp%s%s -> %s\n", opt->scene,
          opt->seq_first, opt->seq_last, s->fps, s->w, s->h, s->spp,
          k ? (opt->reference_only ? ", reference only x" : ", reference x") : "",
          k ? (k == 2   ? "2"
               : k == 4 ? "4"
                        : "K")
            : "",
          s->dir);
}

static int tt__seq_step(tt__seq *s, uint32_t f);
static int tt__seq_commit_frames(tt__seq *s, uint32_t n);

/* Create: the output folder, the session (scene, plugins, accel, integrator, a film with
 * depth and motion), the post-filter, the buffers and the manifest. An exit code; close the
 * sequence in any case. */
static int tt__seq_create(tt__seq *s, const tt__host_options *opt) {
  memset(s, 0, sizeof *s);
  s->opt = opt;
  s->step = tt__seq_step;
  s->commit_frames = tt__seq_commit_frames;
  int rc = tt__seq_dirs(s);
  if (rc == TT_EXIT_OK) rc = tt__session_open(&s->ses, opt);
  if (rc == TT_EXIT_OK) rc = tt__seq_pick_post(s);
  if (rc != TT_EXIT_OK) return rc;
  const tt_render_settings *settings = tt_scene_settings(s->ses.scene);
  s->seed = opt->seed_set ? opt->seed : settings->seed;
  s->spp = opt->spp ? opt->spp : settings->spp;
  /* a still scene's prevdepth is the host's own (from depth and the poses); an animated
   * scene's comes from the film, which knows where each hit was (objects move too) */
  s->animated = tt_scene_animated(s->ses.scene);
  rc = tt__session_start(&s->ses, TT_AOV_DEPTH | TT_AOV_MOTION |
                                      (s->animated ? TT_AOV_PREV_DEPTH : 0) |
                                      (opt->aov_mask & ~TT__AOV_PREVDEPTH));
  if (rc != TT_EXIT_OK) return rc;
  s->w = s->ses.camera->width;
  s->h = s->ses.camera->height;
  s->k = opt->reference_scale;
  s->fps = opt->fps > 0 ? opt->fps : 24.0;
  s->render_frame = !opt->reference_only || opt->aov_mask;
  rc = tt__seq_buffers(s);
  if (rc == TT_EXIT_OK) rc = tt__seq_manifest_open(s);
  if (rc == TT_EXIT_OK) tt__seq_log_start(s);
  if (rc == TT_EXIT_OK) rc = opt->hybrid ? tt__seq_hybrid_create(s) : tt__seq_tune_create(s);
  return rc;
}

/* Writes frame f's `what` (w x h x ch) into the folder and names it in the manifest under
 * `key`. An exit code. */
static int tt__seq_emit(tt__seq *s, tt__seq_file what, const char *key, uint32_t f, uint32_t ch,
                        const float *px, const char *const *names) {
  char name[1024], path[4096 + 1100];
  tt__seq_name(s, what, f, name, sizeof name);
  snprintf(path, sizeof path, "%s/%s", s->dir, name);
  if (tt__seq_write(path, s->w, s->h, ch, px, names)) return TT_EXIT_OUTPUT;
  fprintf(s->manifest, ", \"%s\": \"%s\"", key, name);
  return TT_EXIT_OK;
}

/* The frame's poses and jitter; starts its manifest entry. */
static void tt__seq_frame_begin(tt__seq *s, tt__seq_frame *fr, uint32_t f) {
  memset(fr, 0, sizeof *fr);
  fr->f = f;
  tt_scene_camera_at(s->ses.scene, f / s->fps, &fr->cam);
  tt_scene_camera_at(s->ses.scene, (f - 1.0) / s->fps, &fr->prev);
  fr->cam.width = fr->prev.width = s->w;
  fr->cam.height = fr->prev.height = s->h;
  fr->ji = f % TT__SEQ_JITTER_CYCLE;
  tt_jitter_halton23(fr->ji, fr->jit);
  s->entry_open = 1;
  int first = f == s->opt->seq_first;
  fprintf(s->manifest,
          "    %s{\"index\": %u, \"time\": %.6f, \"jitter_index\": %u, "
          "\"jitter\": [%.6f, %.6f], \"reset\": %s",
          first ? "" : ",", f, f / s->fps, fr->ji, fr->jit[0], fr->jit[1],
          first ? "true" : "false");
}

/* The one place an animated scene moves: the scene posed at frame f's time and the accel
 * updated (refit or rebuild, as the accel's configuration says; built from scratch with
 * s->switch_config when tuning changes the configuration at this frame), recorded in the
 * manifest and in s->update_ms. */
static int tt__seq_update(tt__seq *s, const tt__seq_frame *fr) {
  s->update_ms = 0;
  if (!s->animated) return TT_EXIT_OK;
  tt_accel_update_stats us = {.struct_size = sizeof us};
  const tt_config *cfg = s->switch_config;
  s->switch_config = NULL;
  if (tt_session_set_time_config(s->ses.lib, fr->f / s->fps, 1.0 / s->fps, cfg, &us) != TT_OK) {
    tt__say("frame %u: %s\n", fr->f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  s->update_ms = us.update_ms;
  fprintf(s->manifest, ", \"update\": \"%s\", \"update_ms\": %.3f",
          us.rebuilt ? "rebuild" : "refit", us.update_ms);
  if (us.sah_cost > 0) fprintf(s->manifest, ", \"sah_cost\": %.4f", us.sah_cost);
  return TT_EXIT_OK;
}

/* The jittered frame: rendered, its motion and previous depth kept for the post-filter, and
 * the colour and the asked-for AOVs written. */
static int tt__seq_render_frame(tt__seq *s, tt__seq_frame *fr) {
  static const char *const depth_names[] = {"Z"};
  static const char *const motion_names[] = {"X", "Y"};
  static const char *const normal_names[] = {"X", "Y", "Z"}, *const albedo_names[] = {"R", "G",
                                                                                      "B"};
  const tt__host_options *opt = s->opt;
  const tt_host *host = s->ses.host;
  tt_film *film = s->ses.film;
  size_t px = (size_t)s->w * s->h;
  uint64_t t0 = host->clock_ns();
  if (tt__seq_render(s, film, &fr->cam, &fr->prev, fr->jit, s->seed + fr->f, s->rgb) != TT_OK) {
    tt__say("frame %u: %s\n", fr->f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  fr->render_ms = s->render_ms = (host->clock_ns() - t0) * 1e-6;
  fr->depth = tt_film_aov_const(film, TT_AOV_DEPTH);
  memcpy(s->motion, tt_film_aov_const(film, TT_AOV_MOTION), px * 2 * sizeof(float));
  if (s->animated)
    memcpy(s->prev_depth, tt_film_aov_const(film, TT_AOV_PREV_DEPTH), px * sizeof(float));
  else tt__seq_prev_depth(&fr->cam, &fr->prev, fr->jit, fr->depth, s->w, s->h, s->prev_depth);
  const struct {
    tt__seq_file what;
    const char *key;
    int on;
    uint32_t ch;
    const float *px;
    const char *const *names;
  } files[] = {
      {TT__SEQ_COLOR, "color", !opt->reference_only, 3, s->rgb, NULL},
      {TT__SEQ_DEPTH, "depth", !!(opt->aov_mask & TT__AOV_DEPTH), 1, fr->depth, depth_names},
      {TT__SEQ_MOTION, "motion", !!(opt->aov_mask & TT__AOV_MOTION), 2, s->motion, motion_names},
      {TT__SEQ_NORMAL, "normal", !!(opt->aov_mask & TT__AOV_NORMAL), 3,
       tt_film_aov_const(film, TT_AOV_NORMAL), normal_names},
      {TT__SEQ_ALBEDO, "albedo", !!(opt->aov_mask & TT__AOV_ALBEDO), 3,
       tt_film_aov_const(film, TT_AOV_ALBEDO), albedo_names},
      {TT__SEQ_PREVDEPTH, "prev_depth", !!(opt->aov_mask & TT__AOV_PREVDEPTH), 1, s->prev_depth,
       depth_names},
  };
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    if (!files[i].on) continue;
    int rc = tt__seq_emit(s, files[i].what, files[i].key, fr->f, files[i].ch, files[i].px,
                          files[i].names);
    if (rc != TT_EXIT_OK) return rc;
  }
  return TT_EXIT_OK;
}

/* The reference frame: the pose at k times the resolution per axis with random sub-pixel
 * positions, downsampled with the Blackman-Harris filter, written. */
static int tt__seq_reference(tt__seq *s, tt__seq_frame *fr) {
  if (!s->k) return TT_EXIT_OK;
  tt_camera hi = fr->cam;
  hi.width = s->w * s->k;
  hi.height = s->h * s->k;
  uint64_t r0 = s->ses.host->clock_ns();
  uint64_t seed = s->seed + 1000003u * (fr->f + 1);
  if (tt__seq_render(s, s->ref_film, &hi, NULL, NULL, seed, s->ref_hi) != TT_OK) {
    tt__say("reference frame %u: %s\n", fr->f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  tt__downsample_bh(s->ref_hi, s->k, s->w, s->h, TT__SEQ_BH_RADIUS, s->ref);
  fr->ref_ms = (s->ses.host->clock_ns() - r0) * 1e-6;
  return tt__seq_emit(s, TT__SEQ_REFERENCE, "reference", fr->f, 3, s->ref, NULL);
}

/* The post-filter over the frame (its history reset on the first frame), written. */
static int tt__seq_post(tt__seq *s, const tt__seq_frame *fr) {
  if (!s->post) return TT_EXIT_OK;
  tt_post_frame pf;
  memset(&pf, 0, sizeof pf);
  pf.struct_size = sizeof pf;
  pf.width = s->w;
  pf.height = s->h;
  pf.color = s->rgb;
  pf.depth = fr->depth;
  pf.motion = s->motion;
  pf.frame_index = fr->f - s->opt->seq_first;
  pf.jitter_index = fr->ji;
  pf.jitter[0] = fr->jit[0];
  pf.jitter[1] = fr->jit[1];
  pf.reset_history = fr->f == s->opt->seq_first;
  pf.prev_depth = s->prev_depth;
  uint64_t p0 = s->ses.host->clock_ns();
  if (s->pi->process(s->post, &pf, s->post_rgb) != TT_OK) {
    tt__say("post-filter %s: frame %u: %s\n", s->post_name, fr->f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  double post_ms = (s->ses.host->clock_ns() - p0) * 1e-6;
  int rc = tt__seq_emit(s, TT__SEQ_POST, "post", fr->f, 3, s->post_rgb, NULL);
  if (rc == TT_EXIT_OK) fprintf(s->manifest, ", \"post_ms\": %.3f", post_ms);
  return rc;
}

/* --png: the frame the pattern names (tt__seq_main_file), through the display transform of
 * stills. */
static int tt__seq_png(tt__seq *s, const tt__seq_frame *fr) {
  if (!s->opt->png) return TT_EXIT_OK;
  tt__seq_file main = tt__seq_main_file(s);
  const float *px = main == TT__SEQ_REFERENCE ? s->ref
                    : main == TT__SEQ_POST    ? s->post_rgb
                                              : s->rgb;
  char name[1024], path[4096 + 1100];
  tt__seq_name(s, main, fr->f, name, sizeof name);
  size_t len = strlen(name);
  if (len > 4) memcpy(name + len - 4, ".png", 4); /* every frame name ends in .exr */
  snprintf(path, sizeof path, "%s/%s", s->dir, name);
  tt_image_meta meta[] = {{"software", "tunetrace " TT_VERSION_STRING}};
  if (tt_image_write_png_display(path, s->w, s->h, px, 0.0f, meta, 1) != TT_OK) {
    tt__say("cannot write %s: %s\n", path, tt_last_error());
    return TT_EXIT_OUTPUT;
  }
  fprintf(s->manifest, ", \"png\": \"%s\"", name);
  return TT_EXIT_OK;
}

/* Step: frame f, with the stop held back so that it completes: pose and accel update, the
 * jittered frame, the reference, the post-filter, the PNG; its manifest entry closed and
 * the manifest committed. An exit code (a failure leaves the entry open: finish closes it). */
static int tt__seq_step(tt__seq *s, uint32_t f) {
  tt__seq_frame fr;
  s->render_ms = 0;
  tt_default_host_hold_stop(1);
  tt__seq_frame_begin(s, &fr, f);
  int rc = tt__seq_update(s, &fr);
  if (rc == TT_EXIT_OK && s->render_frame) rc = tt__seq_render_frame(s, &fr);
  if (rc == TT_EXIT_OK) rc = tt__seq_reference(s, &fr);
  if (rc == TT_EXIT_OK) rc = tt__seq_post(s, &fr);
  if (rc == TT_EXIT_OK) rc = tt__seq_png(s, &fr);
  if (rc != TT_EXIT_OK) return rc;
  if (s->frame_note) fputs(s->frame_note, s->manifest);
  fprintf(s->manifest, ", \"render_ms\": %.3f, \"reference_ms\": %.3f}\n", fr.render_ms, fr.ref_ms);
  s->entry_open = 0;
  if (!s->defer_commit) rc = tt__seq_commit_frames(s, 1);
  tt_default_host_hold_stop(0);
  return rc;
}

static int tt__seq_commit_frames(tt__seq *s, uint32_t n) {
  int rc = TT_EXIT_OK;
  if (tt__seq_manifest_commit(s->mpath, s->manifest, &s->mbuf, &s->mlen)) rc = TT_EXIT_OUTPUT;
  s->done_frames += n;
  uint32_t nframes = s->opt->seq_last - s->opt->seq_first + 1;
  tt__progress_update("sequence", (double)s->done_frames / nframes);
  return rc;
}

/* Frame f, inside a tuning window when tuning along the sequence (a failed frame's window
 * is not reported: nothing is recorded for it). */
static int tt__seq_next_frame(tt__seq *s, uint32_t f) {
  if (!s->tune) return tt__seq_step(s, f);
  int rc = tt__seq_tune_before(s, f);
  if (rc == TT_EXIT_OK) rc = tt__seq_step(s, f);
  s->frame_note = NULL;
  if (rc == TT_EXIT_OK) rc = tt__seq_tune_after(s, f);
  return rc;
}

/* Finish: a frame that failed half-way still closes its manifest entry; the manifest is
 * committed and what was written reported. Returns `rc` or the manifest's failure. */
static int tt__seq_finish(tt__seq *s, int rc) {
  const tt__host_options *opt = s->opt;
  uint32_t nframes = opt->seq_last - opt->seq_first + 1;
  tt_default_host_hold_stop(0);
  if (s->entry_open) fprintf(s->manifest, ", \"incomplete\": true}\n");
  tt__progress_finish();
  if (tt__seq_manifest_commit(s->mpath, s->manifest, &s->mbuf, &s->mlen) && rc == TT_EXIT_OK)
    rc = TT_EXIT_OUTPUT;
  if (!opt->quiet && rc == TT_EXIT_OK) tt__say("wrote %u frames to %s\n", nframes, s->dir);
  else if (rc == TT_EXIT_INTERRUPTED)
    tt__say("interrupted: %u of %u frames written to %s (manifest.json lists them)\n",
            s->done_frames, nframes, s->dir);
  return rc;
}

/* Frees what the sequence holds, at any stage. */
static void tt__seq_close(tt__seq *s) {
  tt__seq_tune_free(s);
  tt__seq_hybrid_free(s);
  if (s->manifest) fclose(s->manifest);
  free(s->mbuf);
  if (s->post) s->pi->destroy(s->post);
  tt_film_destroy(s->ref_film);
  free(s->rgb);
  free(s->ref_hi);
  free(s->ref);
  free(s->post_rgb);
  free(s->motion);
  free(s->prev_depth);
  tt__session_close(&s->ses);
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
  int rc = tt__seq_create(&s, opt);
  if (rc == TT_EXIT_OK && s.hybrid) rc = tt__seq_hybrid_run(&s);
  for (uint32_t f = opt->seq_first; rc == TT_EXIT_OK && !s.hybrid && f <= opt->seq_last; f++) {
    /* a stop asked for during the frame before (or, for the first frame, during the scene
     * loading and accel build) ends the sequence here; the first frame is always completed,
     * as a still completes its first pass: exit 130 comes with what was rendered so far */
    if (f > opt->seq_first && s.ses.host->should_stop()) rc = TT_EXIT_INTERRUPTED;
    else rc = tt__seq_next_frame(&s, f);
  }
  if (s.tune) rc = tt__seq_tune_finish(&s, rc);
  if (s.hybrid) rc = tt__seq_hybrid_finish(&s, rc);
  if (s.manifest) rc = tt__seq_finish(&s, rc);
  tt__seq_close(&s);
  return rc;
}
