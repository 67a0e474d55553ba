/* tunetrace: umbrella header. Include this, or only the headers you need. */
#ifndef TUNETRACE_TUNETRACE_H
#define TUNETRACE_TUNETRACE_H

#include <tunetrace/common.h>
#include <tunetrace/host.h>
#include <tunetrace/params.h>
#include <tunetrace/scene.h>
#include <tunetrace/indicators.h>
#include <tunetrace/ray.h>
#include <tunetrace/camera.h>
#include <tunetrace/film.h>
#include <tunetrace/file.h>
#include <tunetrace/image.h>
#include <tunetrace/sampler.h>
#include <tunetrace/path.h>
#include <tunetrace/bdpt.h>
#include <tunetrace/plugin.h>
#include <tunetrace/accel.h>
#include <tunetrace/integrator.h>
#include <tunetrace/tuner.h>
#include <tunetrace/predictor.h>
#include <tunetrace/post.h>
#include <tunetrace/options.h>
#include <tunetrace/loader.h>
#include <tunetrace/tunedb.h>
#include <tunetrace/tuning_hint.h>
#include <tunetrace/tuning.h>
#include <tunetrace/session.h>
#include <tunetrace/suggest.h>
#include <tunetrace/limits.h>
#include <tunetrace/hybrid.h>

#endif /* TUNETRACE_TUNETRACE_H */
