/* Small scenes the bidirectional tests share (integrator_bdpt, integrator_pssmlt mode=mmlt):
 * a spot light above a smooth glass slab over a diffuse floor, viewed from below the slab's
 * level so that the floor under the slab is seen directly (not through the glass). Its light
 * there (light - glass - glass - floor - camera) has no path-tracer strategy: the delta light
 * cannot be hit and the shadow ray meets the glass. Through a thin parallel slab at near
 * normal incidence that floor gets about (1 - R)^2 of the open floor's irradiance (R the
 * Fresnel reflectance, 0.04 at ior 1.5). CAUSTIC_OPEN is the same without the slab. The
 * centre 6x6 pixels of the 16x16 view lie under the slab and inside the spot's cone. */
#ifndef TT_TEST_CAUSTIC_SCENES_H
#define TT_TEST_CAUSTIC_SCENES_H

#define TT_CAUSTIC_HEAD                                                                            \
  "{\"version\":1,\"camera\":{\"position\":[0,-0.2,2.5],\"target\":[0,-1,0],\"up\":[0,1,0],"       \
  "\"fov\":30,"                                                                                    \
  "\"resolution\":[16,16]},\"materials\":{\"white\":{\"type\":\"diffuse\",\"albedo\":[0.8,0.8,0."  \
  "8]},"                                                                                           \
  "\"glass\":{\"type\":\"dielectric\",\"ior\":1.5}},\"lights\":[{\"type\":\"spot\",\"position\":[" \
  "0,2,0],"                                                                                        \
  "\"direction\":[0,-1,0],\"intensity\":[10,10,10],\"angle\":25}],\"meshes\":["                    \
  "{\"name\":\"floor\",\"material\":\"white\",\"positions\":[-3,-1,-3, 3,-1,-3, 3,-1,3, "          \
  "-3,-1,3],\"indices\":[0,2,1, 0,3,2]}"

static const char *const TT_CAUSTIC =
    TT_CAUSTIC_HEAD ","
                    "{\"name\":\"slab\",\"material\":\"glass\",\"positions\":[-1,0.5,-1, 1,0.5,-1, "
                    "1,0.5,1, -1,0.5,1,"
                    " -1,0.6,-1, 1,0.6,-1, 1,0.6,1, -1,0.6,1],\"indices\":[0,1,2, 0,2,3, 4,6,5, "
                    "4,7,6, 0,5,1, 0,4,5, 3,2,6, 3,6,7,"
                    " 0,3,7, 0,7,4, 1,5,6, 1,6,2]}]}";
static const char *const TT_CAUSTIC_OPEN = TT_CAUSTIC_HEAD "]}";

/* Mean luminance of the centre 6x6 pixels of a 16x16 RGB image. */
static inline double tt_caustic_centre(const float *rgb) {
  double m = 0.0;
  for (int y = 5; y < 11; ++y)
    for (int x = 5; x < 11; ++x) {
      const float *c = rgb + 3 * (y * 16 + x);
      m += (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) / 36.0;
    }
  return m;
}

#endif
