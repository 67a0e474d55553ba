/* Row-major 4x4 matrices shared by the scene loaders' transforms. */
#include "util/mat4.h"

#include <string.h>

/* Row-major 4x4 product r = a * b (r may alias a or b). */
void tt__mat4_mul(double r[16], const double a[16], const double b[16]) {
  double t[16];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double acc = 0;
      for (int k = 0; k < 4; k++) acc += a[4 * i + k] * b[4 * k + j];
      t[4 * i + j] = acc;
    }
  memcpy(r, t, sizeof t);
}
