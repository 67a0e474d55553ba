/* Prints the C layout of the structs the Python API mirrors with ctypes (python/tunetrace/
 * _lib.py) as JSON: {"struct": {"size": N, "fields": {"name": offset, ...}}, ...}.
 * python/tests/python_api.py compares it with the ctypes layout, so a header change that the
 * bindings miss fails the suite instead of corrupting memory. */
#include <tunetrace/tunetrace.h>

#include <stddef.h>
#include <stdio.h>

static int first_struct = 1, first_field;

static void begin(const char *name, size_t size) {
  printf("%s\"%s\": {\"size\": %zu, \"fields\": {", first_struct ? "" : ",\n", name, size);
  first_struct = 0;
  first_field = 1;
}
static void field(const char *name, size_t offset) {
  printf("%s\"%s\": %zu", first_field ? "" : ", ", name, offset);
  first_field = 0;
}
static void end(void) { printf("}}"); }

#define S(type) begin(#type, sizeof(type))
#define F(type, f) field(#f, offsetof(type, f))

int main(void) {
  printf("{");
  S(tt_plugin);
  F(tt_plugin, struct_size);
  F(tt_plugin, abi_major);
  F(tt_plugin, abi_minor);
  F(tt_plugin, kind);
  F(tt_plugin, name);
  F(tt_plugin, version);
  F(tt_plugin, description);
  F(tt_plugin, init);
  F(tt_plugin, deinit);
  F(tt_plugin, get_interface);
  end();
  S(tt_camera);
  F(tt_camera, struct_size);
  F(tt_camera, position);
  F(tt_camera, target);
  F(tt_camera, up);
  F(tt_camera, fov_y);
  F(tt_camera, width);
  F(tt_camera, height);
  F(tt_camera, key_count);
  F(tt_camera, keys);
  end();
  S(tt_pass_stats);
  F(tt_pass_stats, struct_size);
  F(tt_pass_stats, time_ms);
  F(tt_pass_stats, rays);
  F(tt_pass_stats, samples);
  F(tt_pass_stats, nonfinite);
  F(tt_pass_stats, metric_count);
  F(tt_pass_stats, metrics);
  end();
  S(tt_accel_build_stats);
  F(tt_accel_build_stats, struct_size);
  F(tt_accel_build_stats, build_ms);
  F(tt_accel_build_stats, memory_bytes);
  F(tt_accel_build_stats, nodes);
  F(tt_accel_build_stats, leaves);
  F(tt_accel_build_stats, sah_cost);
  F(tt_accel_build_stats, max_depth);
  F(tt_accel_build_stats, repaired);
  end();
  S(tt_session_stats);
  F(tt_session_stats, struct_size);
  F(tt_session_stats, passes);
  F(tt_session_stats, spp);
  F(tt_session_stats, total_spp);
  F(tt_session_stats, render_ms);
  F(tt_session_stats, rays);
  F(tt_session_stats, samples);
  F(tt_session_stats, nonfinite);
  F(tt_session_stats, build_ms);
  F(tt_session_stats, build);
  F(tt_session_stats, last_pass);
  F(tt_session_stats, metric_sums);
  F(tt_session_stats, seed);
  end();
  S(tt_tuning_state);
  F(tt_tuning_state, struct_size);
  F(tt_tuning_state, scene_id);
  F(tt_tuning_state, scene);
  F(tt_tuning_state, camera);
  F(tt_tuning_state, context);
  F(tt_tuning_state, has_indicators);
  F(tt_tuning_state, indicators);
  end();
  S(tt_tuning_sample);
  F(tt_tuning_sample, struct_size);
  F(tt_tuning_sample, iteration);
  F(tt_tuning_sample, config);
  F(tt_tuning_sample, cost);
  F(tt_tuning_sample, build_ms);
  F(tt_tuning_sample, render_ms);
  F(tt_tuning_sample, status);
  F(tt_tuning_sample, cached);
  F(tt_tuning_sample, image);
  end();
  S(tt_tuning_measurement);
  F(tt_tuning_measurement, struct_size);
  F(tt_tuning_measurement, status);
  F(tt_tuning_measurement, build_ms);
  F(tt_tuning_measurement, render_ms);
  field("pass_", offsetof(tt_tuning_measurement, pass));
  F(tt_tuning_measurement, image);
  end();
  S(tt_tuning_target);
  F(tt_tuning_target, struct_size);
  F(tt_tuning_target, user);
  F(tt_tuning_target, apply);
  F(tt_tuning_target, render);
  end();
  S(tt_tuning_desc);
  F(tt_tuning_desc, struct_size);
  F(tt_tuning_desc, host);
  F(tt_tuning_desc, space);
  F(tt_tuning_desc, start);
  F(tt_tuning_desc, search);
  F(tt_tuning_desc, objective);
  F(tt_tuning_desc, tuner);
  F(tt_tuning_desc, tuner_settings);
  F(tt_tuning_desc, tuner_name);
  F(tt_tuning_desc, seed);
  F(tt_tuning_desc, iterations);
  F(tt_tuning_desc, spp);
  F(tt_tuning_desc, warmup_passes);
  F(tt_tuning_desc, time_budget_s);
  F(tt_tuning_desc, plugin);
  F(tt_tuning_desc, plugin_version);
  F(tt_tuning_desc, db);
  F(tt_tuning_desc, state);
  F(tt_tuning_desc, run_id);
  F(tt_tuning_desc, width);
  F(tt_tuning_desc, height);
  F(tt_tuning_desc, reference_luminance);
  F(tt_tuning_desc, want_images);
  F(tt_tuning_desc, on_sample);
  F(tt_tuning_desc, user);
  F(tt_tuning_desc, mode);
  end();
  S(tt_tuning_stats);
  F(tt_tuning_stats, struct_size);
  F(tt_tuning_stats, requested);
  F(tt_tuning_stats, iterations);
  F(tt_tuning_stats, measured);
  F(tt_tuning_stats, cached);
  F(tt_tuning_stats, infeasible);
  F(tt_tuning_stats, failed);
  F(tt_tuning_stats, converged);
  F(tt_tuning_stats, interrupted);
  F(tt_tuning_stats, tuning_ms);
  F(tt_tuning_stats, unrecorded);
  F(tt_tuning_stats, remeasured);
  end();
  S(tt_tuning_verification);
  F(tt_tuning_verification, struct_size);
  F(tt_tuning_verification, rounds);
  F(tt_tuning_verification, spp);
  F(tt_tuning_verification, median_build_ms);
  F(tt_tuning_verification, median_render_ms);
  F(tt_tuning_verification, median_total_ms);
  F(tt_tuning_verification, median_cost);
  F(tt_tuning_verification, render_ratio);
  F(tt_tuning_verification, total_ratio);
  F(tt_tuning_verification, cost_ratio);
  F(tt_tuning_verification, rounds_ms);
  F(tt_tuning_verification, verdict);
  F(tt_tuning_verification, best_faster);
  F(tt_tuning_verification, cost_difference);
  F(tt_tuning_verification, reason);
  end();
  S(tt_tunedb_row);
  F(tt_tunedb_row, struct_size);
  F(tt_tunedb_row, id);
  F(tt_tunedb_row, scene_id);
  F(tt_tunedb_row, scene);
  F(tt_tunedb_row, camera);
  F(tt_tunedb_row, context);
  F(tt_tunedb_row, has_indicators);
  F(tt_tunedb_row, indicators);
  F(tt_tunedb_row, plugin);
  F(tt_tunedb_row, plugin_version);
  F(tt_tunedb_row, config);
  F(tt_tunedb_row, objective);
  F(tt_tunedb_row, build_ms);
  F(tt_tunedb_row, render_ms);
  F(tt_tunedb_row, cost);
  F(tt_tunedb_row, status);
  F(tt_tunedb_row, mode);
  F(tt_tunedb_row, iteration);
  F(tt_tunedb_row, run_id);
  F(tt_tunedb_row, tuner);
  F(tt_tunedb_row, metrics);
  F(tt_tunedb_row, machine);
  F(tt_tunedb_row, cpu);
  F(tt_tunedb_row, timestamp);
  F(tt_tunedb_row, host);
  F(tt_tunedb_row, has_rank);
  F(tt_tunedb_row, rank);
  end();
  S(tt_tuning_hint);
  F(tt_tuning_hint, struct_size);
  F(tt_tuning_hint, objective);
  F(tt_tuning_hint, tunable);
  F(tt_tuning_hint, setup);
  end();
  S(tt_tuning_plan);
  F(tt_tuning_plan, struct_size);
  F(tt_tuning_plan, target_index);
  F(tt_tuning_plan, target);
  F(tt_tuning_plan, space);
  F(tt_tuning_plan, search);
  F(tt_tuning_plan, objective);
  end();
  S(tt_option_info);
  F(tt_option_info, key);
  F(tt_option_info, description);
  end();
  S(tt_options_iface);
  F(tt_options_iface, struct_size);
  F(tt_options_iface, count);
  F(tt_options_iface, info);
  F(tt_options_iface, set);
  F(tt_options_iface, get);
  end();
  printf(",\n\"constants\": {\"TT_MAX_METRICS\": %d, \"TT_SCENE_INDICATOR_COUNT\": %d, "
         "\"TT_COST_INFEASIBLE\": %.17g, \"TT_KIND_COUNT\": %d",
         TT_MAX_METRICS, TT_SCENE_INDICATOR_COUNT, (double)TT_COST_INFEASIBLE, TT_KIND_COUNT);
  /* the status codes as the header spells them: the package takes them from the library by
   * name (tt_status_name) and must find the same numbers */
#define STATUS(code) printf(", \"" #code "\": %d", (int)code)
  STATUS(TT_OK);
  STATUS(TT_DONE);
  STATUS(TT_REPAIRED);
  STATUS(TT_ERR_INVALID_ARGUMENT);
  STATUS(TT_ERR_OUT_OF_MEMORY);
  STATUS(TT_ERR_IO);
  STATUS(TT_ERR_PARSE);
  STATUS(TT_ERR_UNSUPPORTED);
  STATUS(TT_ERR_INFEASIBLE);
  STATUS(TT_ERR_ABI);
  STATUS(TT_ERR_NO_DATA);
  STATUS(TT_ERR_INTERRUPTED);
  STATUS(TT_ERR_INTERNAL);
  STATUS(TT_ERR_NUMERIC);
  printf("}}\n");
  return 0;
}
