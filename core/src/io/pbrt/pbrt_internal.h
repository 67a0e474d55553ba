/* pbrt-v4 importer internals: the .pbrt loader (pbrt_parse.c), the PLY reader and analytic
 * shape tessellation (pbrt_shapes.c) and the spectrum-to-RGB approximations
 * (pbrt_spectrum.c). Not part of the public ABI; the mapping is documented in
 * scenes/README.md, "Importing pbrt-v4 scenes". */
#ifndef TT_PBRT_INTERNAL_H
#define TT_PBRT_INTERNAL_H

#include "io/pbrt/pbrt.h"
#include "scene/scene_internal.h"
#include "util/files.h"
#include "util/mat4.h"

#include <stddef.h>

/* ---- shapes (pbrt_shapes.c) ------------------------------------------------------------ */

/* Reads an ASCII or binary PLY file (".ply.gz" too when built with zlib) into triangles;
 * polygons are fanned. `where` ("file:line") prefixes error messages. */
tt_status tt__pbrt_read_ply(const char *path, const char *where, tt__mesh_data *out);

/* Tessellates pbrt's sphere (object space, outward normals, uv = (phi/2pi, theta/pi)). */
tt_status tt__pbrt_sphere(double radius, tt__mesh_data *out);

/* Tessellates pbrt's disk at height z with an optional inner radius; normal +z. */
tt_status tt__pbrt_disk(double radius, double inner, double height, tt__mesh_data *out);

/* One level of Loop subdivision of a closed or open triangle mesh (positions only; uvs and
 * normals are dropped, as pbrt's loopsubdiv computes its own). */
tt_status tt__pbrt_loop_subdivide(tt__mesh_data *mesh);

/* ---- spectra (pbrt_spectrum.c) --------------------------------------------------------- */

/* How a spectrum is turned into RGB: reflectance-like values keep a flat spectrum at 1,
 * illuminants are normalised to luminance 1 (pbrt-v4 divides light spectra by their
 * photometric power). */
typedef enum tt__spectrum_use { TT__SPEC_UNBOUNDED = 0, TT__SPEC_ILLUMINANT = 1 } tt__spectrum_use;

/* Named pbrt-v4 spectra: metal-<X>-eta/k, glass-<X> (a flat IOR), stdillum-*, illum-*.
 * Returns 1 and writes rgb when known, else 0. */
int tt__pbrt_named_spectrum(const char *name, float rgb[3]);

/* RGB of a piecewise-linear spectrum given as (lambda nm, value) pairs. */
void tt__pbrt_sampled_spectrum(const double *pairs, size_t pair_count, tt__spectrum_use use,
                               float rgb[3]);

/* RGB of a blackbody at `kelvin`, normalised to luminance 1 (pbrt-v4's "blackbody"). */
void tt__pbrt_blackbody(double kelvin, float rgb[3]);

#endif /* TT_PBRT_INTERNAL_H */
