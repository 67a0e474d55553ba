// Image I/O behind a C interface: EXR/PNG through OpenImageIO 2.4, the display transform
// through OpenColorIO 2.1. No C++ exception ever crosses into C: every entry point catches
// and turns failures into tt_set_error messages that name the file.
#include <tunetrace/file.h>
#include <tunetrace/image.h>

#include "plugin/log.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace OCIO = OCIO_NAMESPACE;

namespace {

// Metadata prefix for EXR attribute names without a namespace, so our keys never collide
// with standard EXR attributes ("owner", "comments", ...).
const char *const tt__meta_prefix = "tunetrace:";

// The display transform, built once per process (the $OCIO config cannot change under us
// mid-render, and building a processor is costly).
struct tt__display {
  OCIO::ConstCPUProcessorRcPtr cpu;  // null if even the built-in config failed
  std::string name;                  // for tt_image_display_name
  std::string error;                 // why cpu is null
};

std::once_flag tt__display_once;
tt__display tt__display_state;

// Builds the built-in config: scene-linear reference space and an sRGB display space.
// OCIO 2.1 has no ocio:// built-in configs, so we assemble it in code.
OCIO::ConstConfigRcPtr tt__builtin_config() {
  OCIO::ConfigRcPtr cfg = OCIO::Config::Create();
  OCIO::ColorSpaceRcPtr lin = OCIO::ColorSpace::Create();
  lin->setName("linear");
  lin->setDescription("scene-linear Rec.709 primaries (reference)");
  cfg->addColorSpace(lin);

  // ExponentWithLinear forward is the sRGB decoding (EOTF-like) curve; inverted it is the
  // sRGB encoding: 12.92 x below the break, 1.055 x^(1/2.4) - 0.055 above.
  OCIO::ExponentWithLinearTransformRcPtr curve = OCIO::ExponentWithLinearTransform::Create();
  const double gamma[4] = {2.4, 2.4, 2.4, 1.0};
  const double offset[4] = {0.055, 0.055, 0.055, 0.0};
  curve->setGamma(gamma);
  curve->setOffset(offset);
  curve->setDirection(OCIO::TRANSFORM_DIR_INVERSE);
  OCIO::ColorSpaceRcPtr srgb = OCIO::ColorSpace::Create();
  srgb->setName("sRGB");
  srgb->setDescription("sRGB display encoding");
  srgb->setTransform(curve, OCIO::COLORSPACE_DIR_FROM_REFERENCE);
  cfg->addColorSpace(srgb);

  cfg->setRole(OCIO::ROLE_SCENE_LINEAR, "linear");
  cfg->setRole(OCIO::ROLE_DEFAULT, "linear");
  cfg->addDisplayView("sRGB", "Standard", "sRGB", "");
  cfg->setActiveDisplays("sRGB");
  cfg->setActiveViews("Standard");
  cfg->validate();
  return cfg;
}

// scene_linear -> default display / default view of `cfg` as a CPU processor.
OCIO::ConstCPUProcessorRcPtr tt__make_processor(const OCIO::ConstConfigRcPtr &cfg,
                                                std::string *display_view) {
  const char *display = cfg->getDefaultDisplay();
  if (!display || !*display) throw OCIO::Exception("config has no display");
  const char *view = cfg->getDefaultView(display);
  if (!view || !*view) throw OCIO::Exception("config has no view for its default display");
  OCIO::DisplayViewTransformRcPtr dvt = OCIO::DisplayViewTransform::Create();
  dvt->setSrc(OCIO::ROLE_SCENE_LINEAR);
  dvt->setDisplay(display);
  dvt->setView(view);
  OCIO::ConstProcessorRcPtr proc = cfg->getProcessor(dvt);
  *display_view = std::string(display) + "/" + view;
  return proc->getDefaultCPUProcessor();
}

// Runs once: $OCIO if set and usable, else the built-in config with a warning (log host).
void tt__display_init() {
  tt__display &d = tt__display_state;
  const char *env = std::getenv("OCIO");
  if (env && *env) {
    try {
      OCIO::ConstConfigRcPtr cfg = OCIO::Config::CreateFromFile(env);
      std::string dv;
      d.cpu = tt__make_processor(cfg, &dv);
      d.name = std::string(env) + " (" + dv + ")";
      return;
    } catch (const std::exception &e) {
      tt__log(TT_LOG_WARN, "OCIO config '%s' unusable (%s); using built-in sRGB", env, e.what());
    }
  }
  try {
    std::string dv;
    d.cpu = tt__make_processor(tt__builtin_config(), &dv);
    d.name = "built-in sRGB (" + dv + ")";
  } catch (const std::exception &e) {
    d.cpu.reset();
    d.error = e.what();
    d.name = "none";
  }
}

// The cached display state; initialised on first use from any thread.
const tt__display &tt__get_display() {
  std::call_once(tt__display_once, tt__display_init);
  return tt__display_state;
}

// w * h * c with overflow checks against size_t; false if it does not fit.
bool tt__count(uint64_t w, uint64_t h, uint64_t c, size_t *out) {
  if (w == 0 || h == 0 || c == 0) return false;
  const uint64_t limit = SIZE_MAX / sizeof(float);
  if (w > limit / h || w * h > limit / c) return false;
  *out = (size_t)(w * h * c);
  return true;
}

// Adds string metadata to an OIIO spec; `prefix_bare` prefixes keys without a namespace.
tt_status tt__add_meta(OIIO::ImageSpec &spec, const char *path, const tt_image_meta *meta,
                       size_t meta_count, bool prefix_bare) {
  if (meta_count && !meta)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: metadata array is NULL", path);
  for (size_t i = 0; i < meta_count; i++) {
    if (!meta[i].key || !*meta[i].key || !meta[i].value)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: metadata entry %zu has no key or value",
                          path, i);
    std::string key = meta[i].key;
    if (prefix_bare && key.find(':') == std::string::npos) key = tt__meta_prefix + key;
    spec.attribute(key, meta[i].value);
  }
  return TT_OK;
}

// Writes `data` of type `fmt` with `spec` to `path` atomically: OIIO encodes into our own
// stream over a temporary file (tunetrace/file.h), which commit checks for every write
// error (OIIO's PNG writer ignores a full disk), fsyncs and renames over `path`. A kill or a
// failure leaves the previous file. Errors name the path.
tt_status tt__write(const char *path, const OIIO::ImageSpec &spec, OIIO::TypeDesc fmt,
                    const void *data) {
  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
  if (!out)
    return tt_set_error(TT_ERR_IO, "%s: cannot create image writer: %s", path,
                        OIIO::geterror().c_str());
  if (!out->supports("ioproxy"))
    return tt_set_error(TT_ERR_UNSUPPORTED, "%s: the %s writer cannot write atomically", path,
                        out->format_name());
  tt_atomic_file *file = nullptr;
  if (tt_atomic_file_open(path, &file) != TT_OK) return TT_ERR_IO;
  OIIO::Filesystem::IOFile io(tt_atomic_file_stream(file), OIIO::Filesystem::IOProxy::Write);
  out->set_ioproxy(&io);
  std::string err;
  if (!out->open(path, spec)) err = "cannot open for writing: " + out->geterror();
  else if (!out->write_image(fmt, data)) err = "write failed: " + out->geterror();
  // close() finishes the file (EXR offset tables, PNG end chunk) through the proxy
  if (!out->close() && err.empty()) err = "close failed: " + out->geterror();
  out.reset();
  if (!err.empty()) {
    tt_atomic_file_abort(file);
    return tt_set_error(TT_ERR_IO, "%s: %s", path, err.c_str());
  }
  return tt_atomic_file_commit(file);  // its message names the path and the OS reason
}

// Clamps to [0, 1], mapping NaN to 0 (a comparison with NaN is false).
inline float tt__clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }

// 2^exposure, then the cached display processor, then clamp; the body of
// tt_image_display_transform without the exception wall.
tt_status tt__display_apply(float *rgb, size_t pixel_count, float exposure) {
  const tt__display &d = tt__get_display();
  if (!d.cpu)
    return tt_set_error(TT_ERR_INTERNAL, "display transform: no OCIO processor: %s",
                        d.error.c_str());
  const float gain = std::exp2(exposure);
  if (gain != 1.0f)
    for (size_t i = 0; i < pixel_count * 3; i++) rgb[i] *= gain;
  // PackedImageDesc takes a width x height; a 1-row image of pixel_count pixels is fine
  // (OCIO processes pixels independently), but its dimensions are long, so chunk to be safe.
  const size_t chunk = (size_t)1 << 24;
  for (size_t start = 0; start < pixel_count; start += chunk) {
    const size_t n = std::min(chunk, pixel_count - start);
    OCIO::PackedImageDesc img(rgb + 3 * start, (long)n, 1, 3);
    d.cpu->apply(img);
  }
  for (size_t i = 0; i < pixel_count * 3; i++) rgb[i] = tt__clamp01(rgb[i]);
  return TT_OK;
}

}  // namespace

extern "C" {

// Float EXR so a round trip is bit-exact; zip compression is lossless.
TT_API tt_status tt_image_write_exr(const char *path, uint32_t width, uint32_t height,
                                    uint32_t channels, const float *pixels,
                                    const char *const *channel_names, const tt_image_meta *meta,
                                    size_t meta_count) {
  if (!path || !*path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "write EXR: path is empty");
  size_t count;
  if (!pixels || !tt__count(width, height, channels, &count) || width > INT32_MAX ||
      height > INT32_MAX || channels > 1024)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: bad image %ux%ux%u or NULL pixels", path,
                        width, height, channels);
  try {
    OIIO::ImageSpec spec((int)width, (int)height, (int)channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames.clear();
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    for (uint32_t c = 0; c < channels; c++) {
      if (channel_names) {
        if (!channel_names[c] || !*channel_names[c])
          return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: channel %u has no name", path, c);
        spec.channelnames.push_back(channel_names[c]);
      } else if (channels == 1) {
        spec.channelnames.push_back("Y");
      } else if (c < 4) {
        spec.channelnames.push_back(rgba[c]);
      } else {
        spec.channelnames.push_back("channel" + std::to_string(c));
      }
    }
    spec.alpha_channel = -1;
    for (uint32_t c = 0; c < channels; c++)
      if (spec.channelnames[c] == "A") spec.alpha_channel = (int)c;
    spec.attribute("compression", "zip");
    tt_status st = tt__add_meta(spec, path, meta, meta_count, true);
    if (st != TT_OK) return st;
    return tt__write(path, spec, OIIO::TypeDesc::FLOAT, pixels);
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_IO, "%s: %s", path, e.what());
  } catch (...) {
    return tt_set_error(TT_ERR_INTERNAL, "%s: unknown exception writing EXR", path);
  }
}

// Display transform then 8-bit quantisation with rounding; metadata becomes PNG text chunks.
TT_API tt_status tt_image_write_png_display(const char *path, uint32_t width, uint32_t height,
                                            const float *rgb, float exposure,
                                            const tt_image_meta *meta, size_t meta_count) {
  if (!path || !*path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "write PNG: path is empty");
  size_t count;
  if (!rgb || !tt__count(width, height, 3, &count) || width > INT32_MAX || height > INT32_MAX)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: bad image %ux%u or NULL pixels", path, width,
                        height);
  try {
    std::vector<float> tmp(rgb, rgb + count);
    tt_status st = tt__display_apply(tmp.data(), count / 3, exposure);
    if (st != TT_OK) {
      const std::string why = tt_last_error();  // copy: tt_set_error rewrites that buffer
      return tt_set_error(st, "%s: %s", path, why.c_str());
    }
    std::vector<unsigned char> bytes(count);
    for (size_t i = 0; i < count; i++)
      bytes[i] = (unsigned char)std::lround(tmp[i] * 255.0f);  // tmp is already in [0, 1]
    OIIO::ImageSpec spec((int)width, (int)height, 3, OIIO::TypeDesc::UINT8);
    st = tt__add_meta(spec, path, meta, meta_count, false);
    if (st != TT_OK) return st;
    return tt__write(path, spec, OIIO::TypeDesc::UINT8, bytes.data());
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_IO, "%s: %s", path, e.what());
  } catch (...) {
    return tt_set_error(TT_ERR_INTERNAL, "%s: unknown exception writing PNG", path);
  }
}

// In-place display transform; the same code path as the PNG writer.
TT_API tt_status tt_image_display_transform(float *rgb, size_t pixel_count, float exposure) {
  if (!rgb && pixel_count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "display transform: NULL pixels");
  try {
    return tt__display_apply(rgb, pixel_count, exposure);
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_INTERNAL, "display transform: %s", e.what());
  } catch (...) {
    return tt_set_error(TT_ERR_INTERNAL, "display transform: unknown exception");
  }
}

// Name of the config and display/view in use; initialises the transform if needed.
TT_API const char *tt_image_display_name(void) {
  try {
    return tt__get_display().name.c_str();
  } catch (...) {
    return "none";
  }
}

// Reads subimage 0, mip 0, all channels as float into malloc'ed memory.
TT_API tt_status tt_image_read(const char *path, uint32_t *width, uint32_t *height,
                               uint32_t *channels, float **pixels) {
  if (!path || !width || !height || !channels || !pixels)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "read image: NULL argument");
  *pixels = nullptr;
  // OpenImageIO would block on a FIFO and read /dev/zero forever: regular files only
  if (tt_file_check_regular(path, "image") != TT_OK) return TT_ERR_IO;
  try {
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in)
      return tt_set_error(TT_ERR_IO, "%s: cannot open image: %s", path, OIIO::geterror().c_str());
    const OIIO::ImageSpec &spec = in->spec();
    size_t count;
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 ||
        !tt__count((uint64_t)spec.width, (uint64_t)spec.height, (uint64_t)spec.nchannels, &count))
      return tt_set_error(TT_ERR_PARSE, "%s: bad image size %dx%dx%d", path, spec.width,
                          spec.height, spec.nchannels);
    float *buf = (float *)std::malloc(count * sizeof(float));
    if (!buf) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: %zu floats", path, count);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, buf)) {
      std::free(buf);
      return tt_set_error(TT_ERR_IO, "%s: read failed: %s", path, in->geterror().c_str());
    }
    *width = (uint32_t)spec.width;
    *height = (uint32_t)spec.height;
    *channels = (uint32_t)spec.nchannels;
    *pixels = buf;
    in->close();
    return TT_OK;
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_IO, "%s: %s", path, e.what());
  } catch (...) {
    return tt_set_error(TT_ERR_INTERNAL, "%s: unknown exception reading image", path);
  }
}

// Looks up `key`, then "tunetrace:key" for bare keys (how tt_image_write_exr stores them).
TT_API tt_status tt_image_read_meta(const char *path, const char *key, char *value, size_t size) {
  if (!path || !key || !*key || !value || size == 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "read metadata: NULL or empty argument");
  value[0] = '\0';
  if (tt_file_check_regular(path, "image") != TT_OK) return TT_ERR_IO;
  try {
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in)
      return tt_set_error(TT_ERR_IO, "%s: cannot open image: %s", path, OIIO::geterror().c_str());
    const OIIO::ImageSpec &spec = in->spec();
    const OIIO::ParamValue *p = spec.find_attribute(key);
    if (!p && !std::strchr(key, ':')) p = spec.find_attribute(std::string(tt__meta_prefix) + key);
    if (!p) return tt_set_error(TT_ERR_NO_DATA, "%s: no metadata '%s'", path, key);
    // get_string formats non-string attributes (ints, floats, matrices) as text.
    std::string s = p->type() == OIIO::TypeDesc::STRING ? std::string(p->get_ustring().string())
                                                        : p->get_string(1 << 20);
    if (s.size() >= size)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "%s: metadata '%s' needs %zu bytes, buffer has %zu", path, key,
                          s.size() + 1, size);
    std::memcpy(value, s.c_str(), s.size() + 1);
    return TT_OK;
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_IO, "%s: %s", path, e.what());
  } catch (...) {
    return tt_set_error(TT_ERR_INTERNAL, "%s: unknown exception reading metadata", path);
  }
}

}  // extern "C"
