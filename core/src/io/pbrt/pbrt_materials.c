/* pbrt-v4 importer: Material / MakeNamedMaterial mapped onto tt_material, the emissive
 * copies area lights need, and Texture (image maps kept, the rest folded to constants). */
#include "io/pbrt/pbrt_internal.h"
#include "plugin/log.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- materials ------------------------------------------------------------------------- */

/* pbrt-v4's roughness -> GGX alpha (TrowbridgeReitz::RoughnessToAlpha is sqrt). */
static float tt__alpha(double r, int remap) {
  if (!(r > 0)) return 0.0f;
  double a = remap ? sqrt(r) : r;
  return (float)(a > 1.0 ? 1.0 : a);
}

/* Reads roughness / uroughness / vroughness (with a prefix for coated materials). */
static tt_status tt__rough(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *prefix,
                           int remap, float alpha[2]) {
  char n0[64], nu[64], nv[64];
  snprintf(n0, sizeof n0, "%sroughness", prefix);
  snprintf(nu, sizeof nu, "%suroughness", prefix);
  snprintf(nv, sizeof nv, "%svroughness", prefix);
  double r = 0, u, v;
  tt_status st;
  if ((st = tt__getf(P, at, pl, n0, &r)) != TT_OK) return st;
  u = v = r;
  if ((st = tt__getf(P, at, pl, nu, &u)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, nv, &v)) != TT_OK) return st;
  alpha[0] = tt__alpha(u, remap);
  alpha[1] = tt__alpha(v, remap);
  return TT_OK;
}

/* Material eta: a float or a spectrum (named glass or sampled: averaged to one IOR). */
static tt_status tt__ior(tt__pp *P, const tt__tok *at, tt__plist *pl, float *ior) {
  tt__texval v = {{*ior, *ior, *ior}, -1};
  int found;
  tt_status st = tt__getc(P, at, pl, "eta", TT__SPEC_UNBOUNDED, 0, &v, &found);
  if (st != TT_OK) return st;
  if (found) {
    float e = (v.rgb[0] + v.rgb[1] + v.rgb[2]) / 3.0f;
    if (!(e > 0))
      return tt__perr(at->file, at->line, "dielectric eta must be positive, got %g", (double)e);
    *ior = e;
  }
  return TT_OK;
}

/* Conductor eta/k (or pbrt-v4's artist-friendly "reflectance"). */
static tt_status tt__metal(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *prefix,
                           tt_material *m) {
  char ne[64], nk[64], nr[64];
  snprintf(ne, sizeof ne, "%seta", prefix);
  snprintf(nk, sizeof nk, "%sk", prefix);
  snprintf(nr, sizeof nr, "%sreflectance", prefix);
  tt__texval e = {{0.200438f, 0.924033f, 1.10221f}, -1}, k = {{3.91295f, 2.45285f, 2.14219f}, -1},
             r;
  int fr;
  tt_status st;
  if ((st = tt__getc(P, at, pl, ne, TT__SPEC_UNBOUNDED, 0, &e, NULL)) != TT_OK) return st;
  if ((st = tt__getc(P, at, pl, nk, TT__SPEC_UNBOUNDED, 0, &k, NULL)) != TT_OK) return st;
  if ((st = tt__getc(P, at, pl, nr, TT__SPEC_UNBOUNDED, 0, &r, &fr)) != TT_OK) return st;
  if (fr) {
    /* pbrt-v4: eta = 1, k = 2 sqrt(r) / sqrt(1 - r) */
    for (int i = 0; i < 3; i++) {
      double rr = r.rgb[i] < 0 ? 0 : r.rgb[i] > 0.9999 ? 0.9999 : r.rgb[i];
      e.rgb[i] = 1.0f;
      k.rgb[i] = (float)(2 * sqrt(rr) / sqrt(1 - rr));
    }
  }
  for (int i = 0; i < 3; i++) {
    m->eta[i] = e.rgb[i] > 1e-3f ? e.rgb[i] : 1e-3f;
    m->k[i] = k.rgb[i] > 0 ? k.rgb[i] : 0.0f;
  }
  return TT_OK;
}

/* Creates a tt_material from a pbrt material type and its parameters; *out is the scene
 * index, or TT__MAT_INTERFACE for "interface" (no surface). */
tt_status tt__make_material(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl,
                            const char *name, int32_t *out) {
  tt_status st;
  char what[160];
  snprintf(what, sizeof what, "Material \"%s\"", type);
  /* parameters that only steer pbrt's own sampling: nothing to map, nothing to warn */
  static const char *const quiet[] = {"remaproughness", "maxdepth",   "nsamples", "g",
                                      "thickness",      "regularize", NULL};
  int remap = 1;
  if ((st = tt__getb(P, at, pl, "remaproughness", &remap)) != TT_OK) return st;
  for (int i = 0; quiet[i]; i++) tt__find(pl, quiet[i]);
  /* pbrt-v4 material parameters tunetrace does not render: known (a warning, not an error
   * under --strict: the bathroom and staircase scenes of ../shared use displacement) */
  static const char *const unrendered[] = {"displacement", "normalmap", NULL};
  for (int i = 0; unrendered[i]; i++)
    if (tt__find(pl, unrendered[i]))
      tt__pwarn(P, at->file, at->line, unrendered[i], "%s: \"%s\" is not supported (ignored)", what,
                unrendered[i]);
  if (strcmp(type, "interface") == 0 || strcmp(type, "none") == 0 || strcmp(type, "") == 0) {
    *out = TT__MAT_INTERFACE;
    tt__unused(P, at, what, pl);
    return TT_OK;
  }
  if (strcmp(type, "mix") == 0) {
    tt__pparam *mp = tt__find(pl, "materials");
    if (!mp || strcmp(mp->type, "string") != 0 || mp->nstr != 2)
      return tt__perr(at->file, at->line, "mix material needs \"string materials\" with two names");
    double amount = 0.5;
    if ((st = tt__getf(P, at, pl, "amount", &amount)) != TT_OK) return st;
    /* pbrt-v4 picks materials[1] with probability `amount`: keep the dominant one */
    const char *pick = amount <= 0.5 ? mp->str[0] : mp->str[1];
    tt__pwarn(P, at->file, at->line, "mix",
              "mix material approximated by its dominant component \"%s\"", pick);
    for (size_t i = P->nnmat; i-- > 0;)
      if (strcmp(P->nmat[i].name, pick) == 0) {
        *out = P->nmat[i].mat;
        tt__unused(P, at, what, pl);
        return TT_OK;
      }
    return tt__perr(at->file, at->line, "mix material: named material \"%s\" is not defined", pick);
  }
  tt_scene *s = P->scene;
  tt_material m;
  memset(&m, 0, sizeof m);
  m.struct_size = sizeof m;
  m.albedo[0] = m.albedo[1] = m.albedo[2] = 0.5f;
  m.albedo_texture = -1;
  m.specular[0] = m.specular[1] = m.specular[2] = 1.0f;
  m.ior = 1.5f;
  static const float cu_eta[3] = {0.200438f, 0.924033f, 1.10221f},
                     cu_k[3] = {3.91295f, 2.45285f, 2.14219f};
  memcpy(m.eta, cu_eta, sizeof m.eta);
  memcpy(m.k, cu_k, sizeof m.k);
  tt__texval refl = {{0.5f, 0.5f, 0.5f}, -1};
  if (strcmp(type, "diffuse") == 0 || strcmp(type, "diffusetransmission") == 0) {
    m.type = TT_MATERIAL_DIFFUSE;
    if (type[7] == 't') {
      refl.rgb[0] = refl.rgb[1] = refl.rgb[2] = 0.25f;
      tt__pwarn(P, at->file, at->line, "diffusetransmission",
                "diffusetransmission approximated by diffuse reflection (transmission dropped)");
      tt__find(pl, "transmittance");
      double sc = 1;
      if ((st = tt__getf(P, at, pl, "scale", &sc)) != TT_OK) return st;
      if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) != TT_OK)
        return st;
      for (int i = 0; i < 3; i++) refl.rgb[i] *= (float)sc;
    } else if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) !=
               TT_OK) {
      return st;
    }
  } else if (strcmp(type, "coateddiffuse") == 0) {
    m.type = TT_MATERIAL_PLASTIC;
    if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) != TT_OK)
      return st;
    if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK) return st;
    if ((st = tt__ior(P, at, pl, &m.ior)) != TT_OK) return st;
    tt__find(pl, "albedo");
  } else if (strcmp(type, "conductor") == 0) {
    m.type = TT_MATERIAL_CONDUCTOR;
    if ((st = tt__metal(P, at, pl, "", &m)) != TT_OK) return st;
    if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK) return st;
  } else if (strcmp(type, "coatedconductor") == 0) {
    m.type = TT_MATERIAL_CONDUCTOR;
    tt__pwarn(P, at->file, at->line, "coatedconductor",
              "coatedconductor approximated by its conductor base (the clear coat is dropped)");
    if ((st = tt__metal(P, at, pl, "conductor.", &m)) != TT_OK) return st;
    float a1[2], a2[2];
    if ((st = tt__rough(P, at, pl, "interface.", remap, a1)) != TT_OK) return st;
    if ((st = tt__rough(P, at, pl, "conductor.", remap, a2)) != TT_OK) return st;
    for (int i = 0; i < 2; i++) m.alpha[i] = a1[i] > a2[i] ? a1[i] : a2[i];
    tt__find(pl, "interface.eta");
    tt__find(pl, "albedo");
  } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "thindielectric") == 0) {
    m.type = TT_MATERIAL_DIELECTRIC;
    if ((st = tt__ior(P, at, pl, &m.ior)) != TT_OK) return st;
    /* dielectric: roughness -> GGX alpha exactly as for conductor (rough glass, Walter 2007).
     * thindielectric has no roughness in pbrt-v4 and stays smooth (alpha 0). */
    if (type[0] == 't')
      tt__pwarn(P, at->file, at->line, "thindielectric",
                "thindielectric approximated by a solid dielectric");
    else if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK) return st;
  } else {
    static const char *const known[] = {"hair", "measured", "subsurface", "coatedconductor", NULL};
    int pbrt_known = 0;
    for (int i = 0; known[i]; i++) pbrt_known |= strcmp(type, known[i]) == 0;
    if (!pbrt_known) return tt__perr(at->file, at->line, "unknown material type \"%s\"", type);
    tt__pwarn(P, at->file, at->line, type, "material \"%s\" is not supported; using diffuse grey",
              type);
    m.type = TT_MATERIAL_DIFFUSE;
    for (size_t i = 0; i < pl->n; i++) pl->p[i].used = 1;
  }
  for (int i = 0; i < 3; i++) m.albedo[i] = refl.rgb[i] > 1.0f ? 1.0f : refl.rgb[i];
  m.albedo_texture = refl.tex;
  tt__unused(P, at, what, pl);
  char nm[512];
  if (name) snprintf(nm, sizeof nm, "%s", name);
  else {
    const char *base = strrchr(at->file->path, '/');
    snprintf(nm, sizeof nm, "%s@%s:%d", type, base ? base + 1 : at->file->path, at->line);
  }
  m.name = tt__strdup(nm);
  if (!m.name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  tt_material *slot =
      tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
  if (!slot) {
    free((void *)m.name);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  *slot = m;
  *out = (int32_t)(s->material_count - 1);
  return TT_OK;
}

/* The material a shape gets: the current one (pbrt's default diffuse if none) with the
 * active area light's emission folded into a derived copy. */
tt_status tt__shape_material(tt__pp *P, int emissive, int32_t *out) {
  int32_t base = P->gs.mat;
  if (base < 0) {
    if (P->default_mat < 0) {
      tt__plist empty = {0};
      tt__tok at = {TK_WORD, "", 0, P->files, 0};
      tt_status st =
          tt__make_material(P, &at, "diffuse", &empty, "pbrt-default-diffuse", &P->default_mat);
      if (st != TT_OK) return st;
    }
    base = P->default_mat;
  }
  if (!emissive) {
    *out = base;
    return TT_OK;
  }
  for (size_t i = 0; i < P->nder; i++) {
    const tt__derived *d = &P->der[i];
    if (d->base == base && d->two_sided == P->gs.two_sided &&
        memcmp(d->L, P->gs.L, sizeof d->L) == 0) {
      *out = d->mat;
      return TT_OK;
    }
  }
  tt_scene *s = P->scene;
  tt_material m = s->materials[base];
  char nm[600];
  snprintf(nm, sizeof nm, "%s+light%zu", m.name ? m.name : "material", P->nder);
  m.name = tt__strdup(nm);
  if (!m.name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  memcpy(m.emission, P->gs.L, sizeof m.emission);
  m.two_sided = P->gs.two_sided;
  tt_material *slot =
      tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
  P->der = tt__grow(P->der, &P->capder, P->nder + 1, sizeof *P->der);
  if (!slot || !P->der) {
    free((void *)m.name);
    if (slot) s->material_count--;
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  *slot = m;
  tt__derived *d = &P->der[P->nder++];
  d->base = base;
  memcpy(d->L, P->gs.L, sizeof d->L);
  d->two_sided = P->gs.two_sided;
  d->mat = *out = (int32_t)(s->material_count - 1);
  return TT_OK;
}

/* ---- textures -------------------------------------------------------------------------- */

/* Texture directive: imagemap keeps its file; scale multiplies; others become constants. */
tt_status tt__texture(tt__pp *P, const tt__tok *at, const char *name, const char *kind,
                      const char *cls, tt__plist *pl) {
  tt_status st;
  int is_float = strcmp(kind, "float") == 0;
  if (!is_float && strcmp(kind, "spectrum") != 0 && strcmp(kind, "color") != 0)
    return tt__perr(at->file, at->line,
                    "Texture \"%s\": type must be \"float\" or \"spectrum\", got \"%s\"", name,
                    kind);
  tt__ntex t;
  memset(&t, 0, sizeof t);
  t.is_float = is_float;
  t.rgb[0] = t.rgb[1] = t.rgb[2] = 1.0f;
  char what[200];
  snprintf(what, sizeof what, "Texture \"%s\" (\"%s\")", name, cls);
  static const char *const quiet[] = {"filter", "maxanisotropy", "wrap", NULL};
  for (int i = 0; quiet[i]; i++) tt__find(pl, quiet[i]);
  double us = 1, vs = 1, ud = 0, vd = 0;
  const char *mapping = NULL;
  if ((st = tt__gets(at, pl, "mapping", &mapping)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "uscale", &us)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "vscale", &vs)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "udelta", &ud)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "vdelta", &vd)) != TT_OK) return st;
  if (us != 1 || vs != 1 || ud != 0 || vd != 0 || (mapping && strcmp(mapping, "uv") != 0))
    tt__pwarn(P, at->file, at->line, "mapping",
              "%s: texture mapping (uscale/vscale/udelta/vdelta/mapping) is not supported (plain "
              "uv used)",
              what);
  if (strcmp(cls, "imagemap") == 0) {
    const char *fn = NULL, *enc = NULL;
    double scale = 1;
    int invert = 0;
    if ((st = tt__gets(at, pl, "filename", &fn)) != TT_OK) return st;
    if ((st = tt__gets(at, pl, "encoding", &enc)) != TT_OK) return st;
    if ((st = tt__getf(P, at, pl, "scale", &scale)) != TT_OK) return st;
    if ((st = tt__getb(P, at, pl, "invert", &invert)) != TT_OK) return st;
    if (invert)
      tt__pwarn(P, at->file, at->line, "invert", "%s: \"invert\" is not supported (ignored)", what);
    if (!fn) return tt__perr(at->file, at->line, "%s: missing \"string filename\"", what);
    char *path = tt__join(at->file->dir, fn, strlen(fn));
    if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    t.rgb[0] = t.rgb[1] = t.rgb[2] = (float)scale;
    if (tt__exists(path)) {
      t.image = path;
      /* pbrt-v4: PNGs default to sRGB, every other format to linear */
      size_t n = strlen(path);
      t.srgb =
          enc ? strcasecmp(enc, "sRGB") == 0 : (n >= 4 && strcasecmp(path + n - 4, ".png") == 0);
      if (enc && strncmp(enc, "gamma", 5) == 0) t.srgb = 1;
    } else {
      tt__pwarn(P, at->file, at->line, "filename",
                "%s: image \"%s\" not found, using a constant 0.5", what, path);
      free(path);
      t.rgb[0] = t.rgb[1] = t.rgb[2] = (float)(0.5 * scale);
    }
  } else if (strcmp(cls, "constant") == 0) {
    tt__texval v = {{1, 1, 1}, -1};
    if ((st = tt__getc(P, at, pl, "value", TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK) return st;
    memcpy(t.rgb, v.rgb, sizeof t.rgb);
  } else if (strcmp(cls, "scale") == 0) {
    /* tex * scale: either may be a texture; the first image found is kept */
    const char *names[2] = {"tex", "scale"};
    for (int k = 0; k < 2; k++) {
      tt__pparam *p = tt__find(pl, names[k]);
      if (!p) continue;
      float f[3] = {1, 1, 1};
      if (strcmp(p->type, "texture") == 0) {
        const tt__ntex *src = tt__lookup_tex(P, p->str[0], is_float);
        if (!src) {
          tt__pwarn(P, at->file, at->line, names[k], "%s: texture \"%s\" is not defined (1 used)",
                    what, p->str[0]);
        } else {
          memcpy(f, src->rgb, sizeof f);
          if (src->image && !t.image) {
            t.image = tt__strdup(src->image);
            t.srgb = src->srgb;
            if (!t.image) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
          } else if (src->image) {
            tt__pwarn(P, at->file, at->line, names[k],
                      "%s: product of two images; the second is averaged away", what);
          }
        }
      } else {
        tt__texval v = {{1, 1, 1}, -1};
        p->used = 0;
        if ((st = tt__getc(P, at, pl, names[k], TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK) {
          free(t.image);
          return st;
        }
        memcpy(f, v.rgb, sizeof f);
      }
      for (int i = 0; i < 3; i++) t.rgb[i] *= f[i];
    }
  } else {
    /* checkerboard, mix, dots, fbm, ...: a constant average with a warning */
    float a[3] = {1, 1, 1}, b[3] = {0, 0, 0};
    const char *n1 = "tex1", *n2 = "tex2";
    if (strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0) {
      a[0] = a[1] = a[2] = 0;
      b[0] = b[1] = b[2] = 1;
    }
    tt__pparam *ps[2] = {tt__find(pl, n1), tt__find(pl, n2)};
    float *dst[2] = {a, b};
    for (int k = 0; k < 2; k++) {
      if (!ps[k]) continue;
      if (strcmp(ps[k]->type, "texture") == 0) {
        const tt__ntex *src = tt__lookup_tex(P, ps[k]->str[0], is_float);
        if (src) memcpy(dst[k], src->rgb, 3 * sizeof(float));
      } else {
        tt__texval v = {{dst[k][0], dst[k][1], dst[k][2]}, -1};
        ps[k]->used = 0;
        if ((st = tt__getc(P, at, pl, k ? n2 : n1, TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK)
          return st;
        memcpy(dst[k], v.rgb, 3 * sizeof(float));
      }
    }
    for (int i = 0; i < 3; i++) t.rgb[i] = 0.5f * (a[i] + b[i]);
    tt__pwarn(P, at->file, at->line, cls,
              "%s: procedural texture \"%s\" replaced by the constant %.3g %.3g %.3g", what, cls,
              (double)t.rgb[0], (double)t.rgb[1], (double)t.rgb[2]);
    for (size_t i = 0; i < pl->n; i++) pl->p[i].used = 1;
  }
  tt__unused(P, at, what, pl);
  t.name = tt__strdup(name);
  P->ntex = tt__grow(P->ntex, &P->capntex, P->nntex + 1, sizeof *P->ntex);
  if (!t.name || !P->ntex) {
    free(t.name);
    free(t.image);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  P->ntex[P->nntex++] = t;
  return TT_OK;
}
