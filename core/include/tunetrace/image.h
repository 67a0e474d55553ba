/* tunetrace: image I/O. EXR and PNG through OpenImageIO; display transform through
 * OpenColorIO (the $OCIO config if set, else a built-in sRGB config). These wrap C++ libraries
 * behind a C interface (core/src/io/image_io.cpp). Thread-safe (OIIO and OCIO are). */
#ifndef TUNETRACE_IMAGE_H
#define TUNETRACE_IMAGE_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A key/value string pair stored in the image header (EXR attributes, PNG text chunks). */
typedef struct tt_image_meta {
  const char *key;
  const char *value;
} tt_image_meta;

/* Writes a linear float image (width x height x channels, interleaved, row-major) to an
 * OpenEXR file with channel names (NULL: R,G,B[,A] or Y) and metadata. Values are stored
 * as 32-bit float, so a round trip is bit-exact. */
TT_API tt_status tt_image_write_exr(const char *path, uint32_t width, uint32_t height,
                                    uint32_t channels, const float *pixels,
                                    const char *const *channel_names, const tt_image_meta *meta,
                                    size_t meta_count);

/* Converts linear scene-referred RGB (in the OCIO config's scene_linear role) to the
 * config's default display/view (sRGB for the built-in config) after multiplying by
 * 2^exposure, and writes an 8-bit PNG. */
TT_API tt_status tt_image_write_png_display(const char *path, uint32_t width, uint32_t height,
                                            const float *rgb, float exposure,
                                            const tt_image_meta *meta, size_t meta_count);

/* Applies the same display transform to a buffer in place (rgb, values end in [0, 1]). */
TT_API tt_status tt_image_display_transform(float *rgb, size_t pixel_count, float exposure);

/* Name of the OCIO config in use and of its display/view, e.g. "built-in sRGB (sRGB/Standard)". */
TT_API const char *tt_image_display_name(void);

/* Reads any image OpenImageIO can read as float. `*pixels` is allocated with malloc-compatible
 * memory: free with tt_free. */
TT_API tt_status tt_image_read(const char *path, uint32_t *width, uint32_t *height,
                               uint32_t *channels, float **pixels);

/* Reads one metadata attribute of an image file into `value` (size `size`); TT_ERR_NO_DATA
 * if absent. */
TT_API tt_status tt_image_read_meta(const char *path, const char *key, char *value, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_IMAGE_H */
