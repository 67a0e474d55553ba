// Albedo textures through OpenImageIO's TextureSystem (issue 4, item 2), behind a C
// interface for path.c. One process-wide shared TextureSystem (its ImageCache is the shared
// OIIO cache), one TextureHandle per texture, periodic wrap, bilinear, MIP-mapped on demand
// (automip) for untiled files. The path sampler has no ray differentials, so lookups pass
// zero derivatives and read the finest level. No C++ exception crosses into C.
//
// Selected with TT_TEXTURES=oiio in the environment (path.c); the default is direct loading,
// which measured faster (plugins/integrator_pt/README.md, "Textures").
#include <tunetrace/common.h>
#include <tunetrace/file.h>

#include <OpenImageIO/texture.h>

#include <cmath>
#include <exception>
#include <mutex>
#include <new>
#include <string>

extern "C" {
typedef struct tt__oiio_tex tt__oiio_tex;
tt_status tt__oiio_tex_open(const char *path, int srgb, tt__oiio_tex **out);
void tt__oiio_tex_close(tt__oiio_tex *t);
void tt__oiio_tex_lookup(const tt__oiio_tex *t, float u, float v, float out[3]);
}

struct tt__oiio_tex {
  OIIO::TextureSystem *ts;
  OIIO::TextureSystem::TextureHandle *handle;
  int channels;
  int srgb;
};

namespace {

std::once_flag tt__ts_once;
OIIO::TextureSystem *tt__ts = nullptr;

// The shared TextureSystem, created once (never destroyed: OIIO owns the shared one).
OIIO::TextureSystem *tt__texture_system() {
  std::call_once(tt__ts_once, [] {
    tt__ts = OIIO::TextureSystem::create(true);
    if (tt__ts) {
      tt__ts->attribute("automip", 1);  // MIP-map untiled, single-level files in the cache
      tt__ts->attribute("autotile", 64);
    }
  });
  return tt__ts;
}

// sRGB decoding of one channel (applied after filtering).
inline float tt__srgb_decode(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

extern "C" tt_status tt__oiio_tex_open(const char *path, int srgb, tt__oiio_tex **out) {
  *out = nullptr;
  // the TextureSystem would block on a FIFO and read /dev/zero forever: regular files only
  if (tt_file_check_regular(path, "texture") != TT_OK) return TT_ERR_IO;
  try {
    OIIO::TextureSystem *ts = tt__texture_system();
    if (!ts) return tt_set_error(TT_ERR_UNSUPPORTED, "texture '%s': no OIIO TextureSystem", path);
    OIIO::ustring name(path);
    OIIO::TextureSystem::TextureHandle *h = ts->get_texture_handle(name);
    const OIIO::ImageSpec *spec = h ? ts->imagespec(h, nullptr) : nullptr;
    if (!spec) {
      std::string err = ts->geterror();
      return tt_set_error(TT_ERR_IO, "texture '%s': %s", path,
                          err.empty() ? "cannot open" : err.c_str());
    }
    tt__oiio_tex *t = new tt__oiio_tex;
    t->ts = ts;
    t->handle = h;
    t->channels = spec->nchannels >= 3 ? 3 : 1;
    t->srgb = srgb;
    *out = t;
    return TT_OK;
  } catch (const std::exception &e) {
    return tt_set_error(TT_ERR_IO, "texture '%s': %s", path, e.what());
  }
}

extern "C" void tt__oiio_tex_close(tt__oiio_tex *t) { delete t; }

extern "C" void tt__oiio_tex_lookup(const tt__oiio_tex *t, float u, float v, float out[3]) {
  // Texture options are per call (OIIO may write into them); kept on the stack.
  OIIO::TextureOpt opt;
  opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
  opt.interpmode = OIIO::TextureOpt::InterpBilinear;
  opt.mipmode = OIIO::TextureOpt::MipModeTrilinear;
  float r[3] = {0.0f, 0.0f, 0.0f};
  // t = 0 is the top row in OIIO; v = 0 is the bottom (OBJ convention).
  if (!t->ts->texture(t->handle, t->ts->get_perthread_info(), opt, u, 1.0f - v, 0.0f, 0.0f, 0.0f,
                      0.0f, t->channels, r)) {
    out[0] = out[1] = out[2] = 0.0f;
    return;
  }
  if (t->channels == 1) r[1] = r[2] = r[0];
  for (int k = 0; k < 3; ++k) out[k] = t->srgb ? tt__srgb_decode(r[k]) : r[k];
}
