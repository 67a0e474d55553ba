/* Row-major 4x4 matrices (mat4.c). Internal to libtunetrace. */
#ifndef TT_UTIL_MAT4_H
#define TT_UTIL_MAT4_H

/* Row-major 4x4 product r = a * b (r may alias a or b). */
void tt__mat4_mul(double r[16], const double a[16], const double b[16]);

#endif /* TT_UTIL_MAT4_H */
