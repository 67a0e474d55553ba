/* accel_embree parameter space, constraint check and error paths: the published space has
 * exactly the thesis Table 3.1 names with Embree's defaults (plus backend {"native",
 * "custom"} and counters), the check repairs minLeafSize > maxLeafSize and non-power-of-two
 * sahBlockSize, custom-only parameters set under the native backend produce exactly one
 * WARN, and bad inputs fail with messages instead of crashing. */
#include "accel_embree_common.h"

#include <cjson/cJSON.h>

/* Host whose log counts WARN messages and keeps the last one. */
static int g_warns;
static char g_last_warn[512];
static tt_host g_host;

/* Counting log: WARNs are recorded, everything is still printed for diagnosis. */
static void counting_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  va_list ap;
  char msg[512];
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (level == TT_LOG_WARN) {
    g_warns++;
    snprintf(g_last_warn, sizeof g_last_warn, "%s", msg);
  }
  fprintf(stderr, "[log %d %s] %s\n", (int)level, plugin ? plugin : "-", msg);
}

/* One expected parameter of Table 3.1. */
typedef struct expect {
  const char *name;
  const char *type; /* "NOM", "INT", "FLOAT" */
  double def;       /* numeric default (bool: 0/1) */
  double min, max;  /* INT/FLOAT range */
  int nvalues;      /* NOM: number of possible values */
} expect;

static const expect table31[] = {
    {"quality", "NOM", 2, 0, 0, 3},       {"branchingFactor", "NOM", 2, 0, 0, 3},
    {"maxDepth", "INT", 32, 8, 64, 0},    {"sahBlockSize", "INT", 1, 1, 32, 0},
    {"minLeafSize", "INT", 1, 1, 32, 0},  {"maxLeafSize", "INT", 32, 1, 32, 0},
    {"travcost", "FLOAT", 1, 0.1, 10, 0}, {"intcost", "FLOAT", 1, 0.1, 10, 0},
    {"static", "NOM", 0, 0, 0, 2},        {"compact", "NOM", 0, 0, 0, 2},
    {"robust", "NOM", 0, 0, 0, 2},
};

/* Finds parameter `name` in the JSON "parameters" array. */
static const cJSON *find_param(const cJSON *root, const char *name) {
  const cJSON *params = cJSON_GetObjectItemCaseSensitive(root, "parameters"), *p;
  cJSON_ArrayForEach(p, params) {
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(p, "name");
    if (cJSON_IsString(n) && strcmp(n->valuestring, name) == 0) return p;
  }
  return NULL;
}

/* Numeric value of a JSON number or boolean. */
static double json_num(const cJSON *v) {
  if (cJSON_IsBool(v)) return cJSON_IsTrue(v) ? 1.0 : 0.0;
  return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

/* The space as JSON (what `host --describe` prints) and through the reading API. */
static void test_space(const tt_space *space) {
  CHECK(space != NULL);
  CHECK(strcmp(tt_space_plugin(space), "accel_embree") == 0);
  CHECK(tt_space_count(space) == 16);
  char *json = tt_space_to_json(space);
  CHECK(json != NULL);
  cJSON *root = cJSON_Parse(json);
  CHECK_MSG(root != NULL, "tt_space_to_json output does not parse: %s", json);
  if (!root) return;
  const cJSON *params = cJSON_GetObjectItemCaseSensitive(root, "parameters");
  CHECK(cJSON_GetArraySize(params) == 16);
  for (size_t k = 0; k < sizeof table31 / sizeof table31[0]; k++) {
    const expect *e = &table31[k];
    CHECK_CONTAINS(json, e->name);
    const cJSON *p = find_param(root, e->name);
    CHECK_MSG(p != NULL, "parameter %s missing", e->name);
    if (!p) continue;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(p, "type");
    CHECK_MSG(cJSON_IsString(type) && strcmp(type->valuestring, e->type) == 0, "%s type", e->name);
    CHECK_NEAR(json_num(cJSON_GetObjectItemCaseSensitive(p, "value")), e->def, 1e-9);
    const cJSON *desc = cJSON_GetObjectItemCaseSensitive(p, "description");
    CHECK_MSG(cJSON_IsString(desc) &&
                  (strstr(desc->valuestring, "native") || strstr(desc->valuestring, "custom")),
              "%s: description must say which backend it acts in", e->name);
    int idx = tt_space_find(space, e->name);
    CHECK(idx >= 0);
    if (idx < 0) continue;
    CHECK_NEAR(tt_space_default(space, (size_t)idx).f, e->def, 1e-9);
    if (e->nvalues) {
      CHECK(tt_space_type(space, (size_t)idx) == TT_PARAM_NOM);
      CHECK(tt_space_nom_count(space, (size_t)idx) == (size_t)e->nvalues);
      CHECK(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(p, "possibleValues")) ==
            e->nvalues);
    } else {
      CHECK_NEAR(tt_space_min(space, (size_t)idx), e->min, 1e-9);
      CHECK_NEAR(tt_space_max(space, (size_t)idx), e->max, 1e-9);
      CHECK_NEAR(json_num(cJSON_GetObjectItemCaseSensitive(p, "min")), e->min, 1e-9);
      CHECK_NEAR(json_num(cJSON_GetObjectItemCaseSensitive(p, "max")), e->max, 1e-9);
    }
  }
  /* Exact NOM value lists. */
  int q = tt_space_find(space, "quality"), bf = tt_space_find(space, "branchingFactor");
  for (size_t k = 0; k < 3; k++) {
    CHECK(tt_space_nom_value(space, (size_t)q, k).i == (int64_t)k + 1);
    CHECK(tt_space_nom_value(space, (size_t)bf, k).i == (int64_t)2 << k);
  }
  int st = tt_space_find(space, "static");
  CHECK(tt_space_nom_value(space, (size_t)st, 0).kind == TT_VALUE_BOOL);
  /* backend: a string NOM {"native", "custom"}; default native (the bench's winner with
   * default parameters, README.md) */
  int be = tt_space_find(space, "backend");
  CHECK(be == 11);
  CHECK(tt_space_nom_count(space, (size_t)be) == 2);
  tt_value bv = tt_space_nom_value(space, (size_t)be, 0);
  CHECK(bv.kind == TT_VALUE_STRING && bv.s && strcmp(bv.s, "native") == 0);
  bv = tt_space_nom_value(space, (size_t)be, 1);
  CHECK(bv.kind == TT_VALUE_STRING && bv.s && strcmp(bv.s, "custom") == 0);
  CHECK(tt_space_default(space, (size_t)be).index == 0);
  const cJSON *bp = find_param(root, "backend");
  const cJSON *bvals = bp ? cJSON_GetObjectItemCaseSensitive(bp, "possibleValues") : NULL;
  CHECK(cJSON_GetArraySize(bvals) == 2 && cJSON_IsString(cJSON_GetArrayItem(bvals, 0)) &&
        strcmp(cJSON_GetArrayItem(bvals, 0)->valuestring, "native") == 0);
  CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(bp, "value")) &&
        strcmp(cJSON_GetObjectItemCaseSensitive(bp, "value")->valuestring, "native") == 0);
  /* counters: instrumentation bool, appended last, default false */
  int cn = tt_space_find(space, "counters");
  CHECK(cn == 12);
  CHECK(tt_space_type(space, (size_t)cn) == TT_PARAM_NOM &&
        tt_space_nom_count(space, (size_t)cn) == 2);
  CHECK(tt_space_default(space, (size_t)cn).i == 0);
  /* what tuners may change (#17 defect 9): counters is a setting; the custom builder's
   * parameters act only with backend custom and compact false; the rest always act */
  CHECK(!tt_space_is_tunable(space, (size_t)cn));
  const cJSON *cp = find_param(root, "counters");
  CHECK(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(cp, "tunable")));
  static const char *const custom_only[] = {"branchingFactor", "maxDepth",    "sahBlockSize",
                                            "minLeafSize",     "maxLeafSize", "travcost",
                                            "intcost"};
  tt_config *cc = tt_config_create(space);
  for (size_t k = 0; k < 7; k++) {
    size_t i = (size_t)tt_space_find(space, custom_only[k]);
    CHECK_MSG(tt_space_is_tunable(space, i) && tt_space_condition_count(space, i) == 2,
              "%s: %zu conditions", custom_only[k], tt_space_condition_count(space, i));
    CHECK(tt_config_set_string(cc, "backend", "native") == TT_OK && !tt_config_is_active(cc, i));
    CHECK(tt_config_set_string(cc, "backend", "custom") == TT_OK && tt_config_is_active(cc, i));
    CHECK(tt_config_set_string(cc, "compact", "true") == TT_OK && !tt_config_is_active(cc, i));
    CHECK(tt_config_set_string(cc, "compact", "false") == TT_OK);
    const cJSON *when =
        cJSON_GetObjectItemCaseSensitive(find_param(root, custom_only[k]), "activeWhen");
    const cJSON *wb = cJSON_GetObjectItemCaseSensitive(when, "backend");
    CHECK(cJSON_GetArraySize(wb) == 1 && !strcmp(cJSON_GetArrayItem(wb, 0)->valuestring, "custom"));
  }
  static const char *const always[] = {"quality", "static", "compact", "robust", "backend"};
  for (size_t k = 0; k < 5; k++) {
    size_t i = (size_t)tt_space_find(space, always[k]);
    CHECK(tt_space_is_tunable(space, i) && tt_space_condition_count(space, i) == 0);
  }
  /* the per-frame update of animated scenes, appended after counters: updateMethod
   * (rebuild by default; refit; instances) always acts; refitInterval with refit and
   * instances, refitSahGrowth (the custom tree's SAH) with refit only. All three are
   * tunable (tuning along a sequence measures each frame's update + render) and
   * motion-only (a still scene's tuning plan leaves them out), as --describe says. */
  int um = tt_space_find(space, "updateMethod");
  CHECK(um == 13 && tt_space_nom_count(space, (size_t)um) == 3 &&
        tt_space_default(space, (size_t)um).index == 0);
  CHECK(tt_space_is_tunable(space, (size_t)um) && tt_space_is_motion_only(space, (size_t)um) &&
        tt_space_condition_count(space, (size_t)um) == 0);
  const cJSON *ump = find_param(root, "updateMethod");
  CHECK(cJSON_GetObjectItemCaseSensitive(ump, "tunable") == NULL &&
        cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(ump, "motionOnly")));
  for (size_t k = 0; k < 5; k++) /* the Table 3.1 parameters act on a still scene too */
    CHECK(!tt_space_is_motion_only(space, (size_t)tt_space_find(space, always[k])));
  static const char *const refit_only[] = {"refitInterval", "refitSahGrowth"};
  for (size_t k = 0; k < 2; k++) {
    int i = tt_space_find(space, refit_only[k]);
    CHECK_MSG(i == 14 + (int)k && tt_space_is_tunable(space, (size_t)i) &&
                  tt_space_is_motion_only(space, (size_t)i) &&
                  tt_space_condition_count(space, (size_t)i) == 1,
              "%s", refit_only[k]);
    CHECK(tt_config_set_string(cc, "updateMethod", "rebuild") == TT_OK &&
          !tt_config_is_active(cc, (size_t)i));
    CHECK(tt_config_set_string(cc, "updateMethod", "refit") == TT_OK &&
          tt_config_is_active(cc, (size_t)i));
    CHECK(tt_config_set_string(cc, "updateMethod", "instances") == TT_OK &&
          tt_config_is_active(cc, (size_t)i) == (k == 0));
    CHECK(tt_space_default(space, (size_t)i).f == 0.0);
  }
  CHECK(tt_config_set_string(cc, "updateMethod", "instances") == TT_OK &&
        tt_config_get_int(cc, "updateMethod", -1) == 2);
  tt_config_destroy(cc);
  /* constraint texts are published */
  CHECK_CONTAINS(json, "minLeafSize <= maxLeafSize");
  CHECK_CONTAINS(json, "Morton");
  CHECK_CONTAINS(json, "branchingFactor^(maxDepth-1)*maxLeafSize");
  CHECK_CONTAINS(json, "power of two");
  CHECK_CONTAINS(json, "travcost/intcost");
  CHECK_CONTAINS(json, "compact=true with backend custom");
  cJSON_Delete(root);
  tt_free(json);
}

/* The check function: defaults feasible; min > max leaf is swapped and reported. */
static void test_check(const tt_space *space) {
  tt_config *c = tt_config_create(space);
  char why[256] = "";
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(tt_config_set_string(c, "minLeafSize", "20") == TT_OK);
  CHECK(tt_config_set_string(c, "maxLeafSize", "6") == TT_OK);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_REPAIRED);
  CHECK_CONTAINS(why, "minLeafSize");
  CHECK(tt_config_get_int(c, "minLeafSize", -1) == 6);
  CHECK(tt_config_get_int(c, "maxLeafSize", -1) == 20);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_OK);
  /* out-of-space values are refused by the config itself, never reach the plugin */
  CHECK(tt_config_set_string(c, "branchingFactor", "16") != TT_OK);
  CHECK(tt_config_set_string(c, "backend", "custom") == TT_OK);
  CHECK(tt_config_set_string(c, "backend", "embree4") != TT_OK);
  CHECK(tt_config_set_string(c, "backend", "native") == TT_OK);
  /* sahBlockSize acts through its largest power of two: 6 -> 4, reported */
  CHECK(tt_config_set_string(c, "sahBlockSize", "6") == TT_OK);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_REPAIRED);
  CHECK_CONTAINS(why, "sahBlockSize 6 acts as 4");
  CHECK(tt_config_get_int(c, "sahBlockSize", -1) == 4);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(tt_config_set_string(c, "sahBlockSize", "32") == TT_OK);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_OK);
  /* both repairs at once are both reported */
  CHECK(tt_config_set_string(c, "sahBlockSize", "31") == TT_OK);
  CHECK(tt_config_set_string(c, "minLeafSize", "30") == TT_OK);
  CHECK(tt_space_check(space, c, why, sizeof why) == TT_CHECK_REPAIRED);
  CHECK_CONTAINS(why, "swapped");
  CHECK_CONTAINS(why, "acts as 16");
  tt_config_destroy(c);
}

/* A tiny two-triangle scene (a quad at z = 0). */
static tt_scene *quad_scene(void) {
  static const float pos[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  static const uint32_t idx[] = {0, 1, 2, 0, 2, 3};
  ae_buf b = {0};
  ae_scene_begin(&b);
  ae_scene_mesh(&b, 1, "quad", pos, 4, idx, 2);
  return ae_scene_end(&b, "quad");
}

/* Build-time behaviour: repair flag, the one-time WARN, and error paths. */
static void test_build(const tt_accel_iface *A) {
  const tt_space *space = A->space();
  tt_scene *scene = quad_scene();
  tt_accel *acc = NULL;
  tt_accel_build_stats st = {.struct_size = sizeof st};

  /* defaults: no WARN, no repair, a hit through the quad */
  g_warns = 0;
  CHECK(A->build(scene, NULL, &acc, &st) == TT_OK && acc);
  CHECK(st.repaired == 0 && st.memory_bytes > 0);
  tt_ray r = {{0.25f, 0.5f, 3.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
  tt_hit h;
  A->intersect1(acc, &r, &h);
  CHECK(h.geom_id == 0 && h.prim_id == 1);
  CHECK_NEAR(h.t, 3.0, 1e-5);
  CHECK_NEAR(r.tfar, 3.0, 1e-5);
  CHECK(h.ng[2] > 0); /* counter-clockwise seen from +z: cross(v1-v0, v2-v0) points at +z */
  r.tfar = INFINITY;
  CHECK(A->occluded1(acc, &r) == 1);
  r.tfar = 2.9f;
  CHECK(A->occluded1(acc, &r) == 0);
  A->destroy(acc);
  CHECK(g_warns == 0);

  /* minLeafSize > maxLeafSize: built after repair, reported in the stats */
  tt_config *c = tt_config_create(space);
  CHECK(tt_config_set_string(c, "minLeafSize", "9") == TT_OK);
  CHECK(tt_config_set_string(c, "maxLeafSize", "3") == TT_OK);
  acc = NULL;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  CHECK(A->build(scene, c, &acc, &st) == TT_OK && acc);
  CHECK(st.repaired != 0);
  CHECK(tt_config_get_int(c, "minLeafSize", -1) == 9); /* the caller's config is const */
  A->destroy(acc);
  /* non-default custom-only parameters under backend native: exactly one WARN, ever */
  CHECK(g_warns == 1);
  CHECK_CONTAINS(g_last_warn, "minLeafSize");
  CHECK_CONTAINS(g_last_warn, "native");
  CHECK(tt_config_set_string(c, "branchingFactor", "8") == TT_OK);
  CHECK(A->build(scene, c, &acc, NULL) == TT_OK && acc);
  A->destroy(acc);
  CHECK(g_warns == 1);
  tt_config_destroy(c);

  /* A truncated stats struct (older caller): only its prefix is written. */
  struct {
    tt_accel_build_stats s;
    char guard[8];
  } small;
  memset(&small, 0x7f, sizeof small);
  small.s.struct_size = (uint32_t)offsetof(tt_accel_build_stats, memory_bytes);
  CHECK(A->build(scene, NULL, &acc, &small.s) == TT_OK && acc);
  CHECK(small.s.build_ms >= 0.0);
  unsigned char *tail = (unsigned char *)&small.s.memory_bytes;
  int untouched = 1;
  for (size_t k = 0; k < sizeof small - offsetof(tt_accel_build_stats, memory_bytes); k++)
    untouched &= tail[k] == 0x7f;
  CHECK(untouched);
  A->destroy(acc);

  /* error paths: clear messages, no crash, *out reset */
  acc = (tt_accel *)&st;
  CHECK(A->build(NULL, NULL, &acc, NULL) == TT_ERR_INVALID_ARGUMENT);
  CHECK(acc == NULL);
  CHECK_CONTAINS(tt_last_error(), "scene is NULL");
  CHECK(A->build(scene, NULL, NULL, NULL) == TT_ERR_INVALID_ARGUMENT);

  tt_space *other = tt_space_create("accel_other", "1.0.0");
  tt_space_add_int(other, "maxDepth", 1, 10, 5, "x");
  tt_config *oc = tt_config_create(other);
  CHECK(A->build(scene, oc, &acc, NULL) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_other");
  tt_config_destroy(oc);
  tt_space_destroy(other);

  /* A configuration of a JSON copy of the space (as a tuning database restores it). */
  char *json = tt_space_to_json(space);
  tt_space *copy = json ? tt_space_from_json(json, "copy") : NULL;
  CHECK(copy != NULL);
  if (copy) {
    tt_config *cc = tt_config_create(copy);
    CHECK(tt_config_set_string(cc, "quality", "3") == TT_OK);
    CHECK(tt_config_set_string(cc, "minLeafSize", "5") == TT_OK);
    CHECK(tt_config_set_string(cc, "maxLeafSize", "4") == TT_OK);
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK(A->build(scene, cc, &acc, &st) == TT_OK && acc);
    CHECK(st.repaired != 0); /* the check runs even without the space's check function */
    A->destroy(acc);
    tt_config_destroy(cc);
    tt_space_destroy(copy);
  }
  tt_free(json);
  tt_scene_destroy(scene);

  /* A scene without triangles is refused with a message, if the loader accepts it. */
  tt_scene *empty = NULL;
  static const char empty_json[] =
      "{\"version\":1,\"camera\":{\"position\":[0,0,5],\"target\":[0,0,0],\"up\":[0,1,0],"
      "\"fov\":45,\"resolution\":[64,64]},\"materials\":{\"m\":{\"type\":\"diffuse\","
      "\"albedo\":[0.5,0.5,0.5]}},\"meshes\":[]}";
  if (tt_scene_load_json(empty_json, strlen(empty_json), "empty", NULL, &empty) == TT_OK) {
    acc = NULL;
    CHECK(A->build(empty, NULL, &acc, NULL) == TT_ERR_INVALID_ARGUMENT);
    CHECK(acc == NULL);
    CHECK_CONTAINS(tt_last_error(), "no triangles");
    tt_scene_destroy(empty);
  } else {
    printf("note: the scene loader refuses a scene without meshes (%s)\n", tt_last_error());
  }
}

int main(void) {
  g_host = *tt_default_host();
  g_host.log = counting_log;
  ae_plugin pl = ae_load(&g_host);
  CHECK(pl.entry->kind == TT_KIND_ACCEL);
  CHECK(strcmp(pl.entry->name, "accel_embree") == 0);
  CHECK(strcmp(pl.entry->version, "0.1.0") == 0);
  CHECK(pl.entry->get_interface("tt.accel/1") == pl.accel);
  CHECK(pl.entry->get_interface("tt.accel/2") == NULL);
  CHECK(pl.entry->get_interface("tt.integrator/1") == NULL);
  CHECK(pl.accel->struct_size == sizeof(tt_accel_iface));
  test_space(pl.accel->space());
  test_check(pl.accel->space());
  test_build(pl.accel);
  tt_registry_destroy(pl.reg);
  return tt_test_finish("accel_embree_space");
}
