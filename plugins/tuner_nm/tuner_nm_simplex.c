/* tuner_nm: the Nelder-Mead simplex of one nominal combination, written as an ask/tell
 * state machine. The driver evaluates the arm's pending point (measurement, cache hit or
 * internal infeasible penalty), stores its cache id and calls tt__nm_arm_receive, which
 * decides the next point. All coordinates live in the unit cube [0,1]^n. */
#include "tuner_nm_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define X(a, t, i) (&(a)->x[(size_t)(i) * (t)->n])

/* Clamps to [0,1] so the simplex never leaves the space (proposals stay inside it). */
static double tt__nm_clamp01(double u) {
  if (!(u >= 0.0)) return 0.0;
  return u > 1.0 ? 1.0 : u;
}

/* Cost of point i of the arm: cache mean, +inf if rejected or not yet evaluated. */
static double tt__nm_cost(const tt_tuner *t, const tt__nm_arm *a, size_t i) {
  return tt__nm_point_cost(t, a->id[i]);
}

/* Standard normal deviate (Box-Muller, no cached spare so the RNG state is one word). */
static double tt__nm_gauss(uint64_t *rng) {
  double u1 = tt__nm_rand(rng), u2 = tt__nm_rand(rng);
  if (u1 < 1e-300) u1 = 1e-300;
  return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* |det| of the n x n edge matrix (x_j - x_0): proportional to the simplex volume. A nearly
 * flat simplex searches only a subspace, so the initialisation keeps the fattest one. */
static double tt__nm_volume(const double *pts, size_t n, double *m) {
  for (size_t j = 0; j < n; j++)
    for (size_t d = 0; d < n; d++) m[j * n + d] = pts[(j + 1) * n + d] - pts[d];
  double det = 1.0;
  for (size_t c = 0; c < n; c++) {
    size_t piv = c;
    for (size_t r = c + 1; r < n; r++)
      if (fabs(m[r * n + c]) > fabs(m[piv * n + c])) piv = r;
    if (m[piv * n + c] == 0.0) return 0.0;
    if (piv != c)
      for (size_t d = 0; d < n; d++) {
        double tmp = m[c * n + d];
        m[c * n + d] = m[piv * n + d];
        m[piv * n + d] = tmp;
      }
    det *= m[c * n + c];
    for (size_t r = c + 1; r < n; r++) {
      double f = m[r * n + c] / m[c * n + c];
      for (size_t d = c; d < n; d++) m[r * n + d] -= f * m[c * n + d];
    }
  }
  return fabs(det);
}

/* Latin hypercube of `count` points in the box [lo, lo+size]^n: in every dimension each of
 * the `count` strata holds exactly one point, jittered uniformly inside its stratum. */
void tt__nm_lhs(tt_tuner *t, double *pts, size_t count, size_t n, const double *lo, double size) {
  size_t *p = malloc(count * sizeof *p);
  if (!p) { /* out of memory: fall back to stratum centres in order (still a valid LHS) */
    for (size_t d = 0; d < n; d++)
      for (size_t j = 0; j < count; j++)
        pts[j * n + d] = lo[d] + size * ((double)j + 0.5) / (double)count;
    return;
  }
  for (size_t d = 0; d < n; d++) {
    for (size_t j = 0; j < count; j++) p[j] = j;
    for (size_t j = count; j > 1; j--) { /* Fisher-Yates */
      size_t r = (size_t)(tt__nm_rand(&t->rng) * (double)j);
      if (r >= j) r = j - 1;
      size_t tmp = p[j - 1];
      p[j - 1] = p[r];
      p[r] = tmp;
    }
    for (size_t j = 0; j < count; j++)
      pts[j * n + d] = lo[d] + size * ((double)p[j] + tt__nm_rand(&t->rng)) / (double)count;
  }
  free(p);
}

/* Draws one candidate simplex of n+1 points with the configured initialisation method. */
static void tt__nm_draw(tt_tuner *t, double *pts, const double *center, const double *lo,
                        double size) {
  size_t n = t->n;
  if (t->set.init == TT__NM_INIT_LHS) {
    tt__nm_lhs(t, pts, n + 1, n, lo, size);
  } else if (t->set.init == TT__NM_INIT_UNIFORM) {
    for (size_t j = 0; j <= n; j++)
      for (size_t d = 0; d < n; d++) pts[j * n + d] = lo[d] + size * tt__nm_rand(&t->rng);
  } else {
    /* Centred normal: sigma = size/4, so +-2 sigma spans the box. */
    for (size_t j = 0; j <= n; j++)
      for (size_t d = 0; d < n; d++)
        pts[j * n + d] = tt__nm_clamp01(center[d] + 0.25 * size * tt__nm_gauss(&t->rng));
  }
}

void tt__nm_arm_generate(tt_tuner *t, tt__nm_arm *a, const double *center, double size,
                         int keep_best) {
  size_t n = t->n;
  a->size = size;
  a->phase = TT__NM_WAIT_INIT;
  for (size_t i = keep_best ? 1 : 0; i < n + 4; i++) a->id[i] = -2;
  if (n == 0) {
    a->k = keep_best ? 1 : 0;
    a->pend = a->k;
    return;
  }
  double s = size > 1.0 ? 1.0 : size;
  /* Scratch: lo (n), best candidate and current candidate ((n+1) n each), matrix (n n). */
  double *buf = malloc(sizeof(double) * (n + 2 * (n + 1) * n + n * n));
  if (!buf) { /* out of memory: a degenerate simplex at the centre still terminates */
    for (size_t j = 0; j <= n; j++)
      if (!(keep_best && j == 0)) memcpy(X(a, t, j), center, n * sizeof(double));
    a->k = keep_best ? 1 : 0;
    a->pend = a->k;
    return;
  }
  double *lo = buf, *best = lo + n, *cand = best + (n + 1) * n, *m = cand + (n + 1) * n;
  for (size_t d = 0; d < n; d++) {
    double l = center[d] - 0.5 * s;
    if (l > 1.0 - s) l = 1.0 - s; /* shift the box inside [0,1] rather than clip it */
    if (l < 0.0) l = 0.0;
    lo[d] = l;
  }
  double best_vol = -1.0;
  for (int tries = 0; tries < TT__NM_INIT_TRIES; tries++) {
    tt__nm_draw(t, cand, center, lo, s);
    if (keep_best) {
      /* Vertex 0 is kept and replaces the drawn point nearest to it, so the restart (or
       * the build of a probed arm) costs n measurements, not n+1. The volume is judged
       * after the replacement: that is the simplex the search will use. */
      size_t nearest = 0;
      double nd = INFINITY;
      for (size_t j = 0; j <= n; j++) {
        double dd = 0.0;
        for (size_t d = 0; d < n; d++) {
          double e = cand[j * n + d] - X(a, t, 0)[d];
          dd += e * e;
        }
        if (dd < nd) nd = dd, nearest = j;
      }
      if (nearest != 0) memcpy(&cand[nearest * n], cand, n * sizeof(double));
      memcpy(cand, X(a, t, 0), n * sizeof(double));
    }
    double vol = tt__nm_volume(cand, n, m);
    if (vol > best_vol) {
      best_vol = vol;
      memcpy(best, cand, (n + 1) * n * sizeof(double));
    }
  }
  if (keep_best) memcpy(X(a, t, 1), &best[n], n * n * sizeof(double));
  else memcpy(a->x, best, (n + 1) * n * sizeof(double));
  free(buf);
  a->k = keep_best ? 1 : 0;
  a->pend = a->k;
}

/* Sorts vertices 0..n by cost, stable, so equal costs keep their (older first) order. */
static void tt__nm_sort(tt_tuner *t, tt__nm_arm *a) {
  size_t n = t->n;
  double tmp[64], *row = n <= 64 ? tmp : malloc(n * sizeof *row);
  if (!row) return;
  for (size_t i = 1; i <= n; i++) {
    size_t j = i;
    while (j > 0 && tt__nm_cost(t, a, j) < tt__nm_cost(t, a, j - 1)) {
      int32_t id = a->id[j];
      a->id[j] = a->id[j - 1];
      a->id[j - 1] = id;
      memcpy(row, X(a, t, j), n * sizeof(double));
      memcpy(X(a, t, j), X(a, t, j - 1), n * sizeof(double));
      memcpy(X(a, t, j - 1), row, n * sizeof(double));
      j--;
    }
  }
  if (row != tmp) free(row);
}

/* Largest Euclidean distance between two vertices. */
static double tt__nm_diameter(const tt_tuner *t, const tt__nm_arm *a) {
  size_t n = t->n;
  double dmax = 0.0;
  for (size_t i = 0; i <= n; i++)
    for (size_t j = i + 1; j <= n; j++) {
      double s = 0.0;
      for (size_t d = 0; d < n; d++) {
        double e = X(a, t, i)[d] - X(a, t, j)[d];
        s += e * e;
      }
      if (s > dmax) dmax = s;
    }
  return sqrt(dmax);
}

/* Writes xo + coef * (from - xo) into point `dst` (clamped), where xo is the centroid of
 * the n best vertices. */
static void tt__nm_along(tt_tuner *t, tt__nm_arm *a, size_t dst, const double *from, double coef) {
  size_t n = t->n;
  for (size_t d = 0; d < n; d++) {
    double xo = 0.0;
    for (size_t i = 0; i < n; i++) xo += X(a, t, i)[d];
    xo /= (double)n;
    X(a, t, dst)[d] = tt__nm_clamp01(xo + coef * (from[d] - xo));
  }
  a->id[dst] = -2;
}

/* Copies trial point `src` over the worst vertex. */
static void tt__nm_replace_worst(tt_tuner *t, tt__nm_arm *a, size_t src) {
  memcpy(X(a, t, t->n), X(a, t, src), t->n * sizeof(double));
  a->id[t->n] = a->id[src];
}

/* Starts an iteration: sort, test convergence (restart or finish), re-measure the incumbent
 * when due, otherwise propose the reflection of the worst vertex. */
static void tt__nm_begin_iteration(tt_tuner *t, tt__nm_arm *a) {
  size_t n = t->n;
  tt__nm_sort(t, a);
  if (n == 0) {
    a->phase = TT__NM_DONE;
    return;
  }
  if (tt__nm_diameter(t, a) < t->set.tolerance) {
    if (a->restarts < t->set.restarts) {
      a->restarts++;
      double size = a->size * 0.5;
      if (size < t->min_restart) size = t->min_restart;
      tt__nm_arm_generate(t, a, X(a, t, 0), size, 1);
    } else {
      a->phase = TT__NM_DONE;
    }
    return;
  }
  int64_t K = t->set.reevaluate;
  int32_t b = a->id[0];
  if (K > 0 && t->deterministic != 1 && a->iter > 0 && a->iter % K == 0 &&
      a->reeval_iter != a->iter && b >= 0 && t->cache.n[b] < TT__NM_REEVAL_CAP &&
      tt__nm_cost(t, a, 0) < TT_COST_INFEASIBLE) {
    a->phase = TT__NM_WAIT_REEVAL;
    a->pend = 0;
    return;
  }
  /* Reflection: xo + alpha (xo - xw) = xo + (-alpha) (xw - xo). */
  tt__nm_along(t, a, n + 1, X(a, t, n), -t->set.reflection);
  a->phase = TT__NM_WAIT_REFLECT;
  a->pend = (int)(n + 1);
}

/* Ends an iteration that replaced or shrank vertices. */
static void tt__nm_finish_iteration(tt_tuner *t, tt__nm_arm *a) {
  a->iter++;
  tt__nm_begin_iteration(t, a);
}

/* Shrinks every vertex towards the best one; they are then re-evaluated one by one. */
static void tt__nm_start_shrink(tt_tuner *t, tt__nm_arm *a) {
  size_t n = t->n;
  for (size_t i = 1; i <= n; i++) {
    for (size_t d = 0; d < n; d++) X(a, t, i)
    [d] = tt__nm_clamp01(X(a, t, 0)[d] + t->set.shrink * (X(a, t, i)[d] - X(a, t, 0)[d]));
    a->id[i] = -2;
  }
  a->phase = TT__NM_WAIT_SHRINK;
  a->k = 1;
  a->pend = 1;
}

void tt__nm_arm_receive(tt_tuner *t, tt__nm_arm *a) {
  size_t n = t->n;
  size_t R = n + 1, E = n + 2, C = n + 3;
  switch (a->phase) {
  case TT__NM_WAIT_PROBE: a->phase = TT__NM_PROBED; return;
  case TT__NM_WAIT_INIT:
    if (++a->k <= (int)n) {
      a->pend = a->k;
      return;
    }
    /* The first full simplex's cost spread is what building an arm typically reveals;
       * the scheduler credits it to arms that are not built yet. */
    if (a->restarts == 0 && isnan(a->init_spread)) a->init_spread = tt__nm_arm_spread(t, a);
    tt__nm_begin_iteration(t, a);
    return;
  case TT__NM_WAIT_REEVAL:
    a->reeval_iter = a->iter;
    tt__nm_begin_iteration(t, a);
    return;
  case TT__NM_WAIT_REFLECT: {
    double fr = tt__nm_cost(t, a, R);
    if (fr < tt__nm_cost(t, a, 0)) {
      tt__nm_along(t, a, E, X(a, t, R), t->set.expansion);
      a->phase = TT__NM_WAIT_EXPAND;
      a->pend = (int)E;
    } else if (fr < tt__nm_cost(t, a, n - 1)) {
      tt__nm_replace_worst(t, a, R);
      tt__nm_finish_iteration(t, a);
    } else if (fr < tt__nm_cost(t, a, n)) {
      tt__nm_along(t, a, C, X(a, t, R), t->set.contraction);
      a->phase = TT__NM_WAIT_CONTRACT_OUT;
      a->pend = (int)C;
    } else {
      tt__nm_along(t, a, C, X(a, t, n), t->set.contraction);
      a->phase = TT__NM_WAIT_CONTRACT_IN;
      a->pend = (int)C;
    }
    return;
  }
  case TT__NM_WAIT_EXPAND:
    tt__nm_replace_worst(t, a, tt__nm_cost(t, a, E) < tt__nm_cost(t, a, R) ? E : R);
    tt__nm_finish_iteration(t, a);
    return;
  case TT__NM_WAIT_CONTRACT_OUT:
    if (tt__nm_cost(t, a, C) <= tt__nm_cost(t, a, R)) {
      tt__nm_replace_worst(t, a, C);
      tt__nm_finish_iteration(t, a);
    } else {
      tt__nm_start_shrink(t, a);
    }
    return;
  case TT__NM_WAIT_CONTRACT_IN:
    if (tt__nm_cost(t, a, C) < tt__nm_cost(t, a, n)) {
      tt__nm_replace_worst(t, a, C);
      tt__nm_finish_iteration(t, a);
    } else {
      tt__nm_start_shrink(t, a);
    }
    return;
  case TT__NM_WAIT_SHRINK:
    if (++a->k <= (int)n) {
      a->pend = a->k;
      return;
    }
    tt__nm_finish_iteration(t, a);
    return;
  default: return;
  }
}

int tt__nm_arm_init_complete(const tt__nm_arm *a) {
  if (a->phase == TT__NM_FRESH) return 0;
  if (a->phase == TT__NM_WAIT_INIT) return a->restarts > 0;
  return 1;
}

/* Probed or partly initialised arms have no simplex to judge them by yet. */
int tt__nm_arm_built(const tt__nm_arm *a) {
  if (a->phase == TT__NM_FRESH || a->phase == TT__NM_WAIT_PROBE || a->phase == TT__NM_PROBED)
    return 0;
  if (a->phase == TT__NM_WAIT_INIT) return a->restarts > 0;
  return 1;
}

/* worst - best over the measured vertices (failed measurements left out); 0 if fewer than
 * two, NaN if none is feasible. */
double tt__nm_arm_spread(const tt_tuner *t, const tt__nm_arm *a) {
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i <= t->n; i++)
    if (a->id[i] >= 0) {
      double c = tt__nm_cost(t, a, i);
      if (c < lo) lo = c;
      if (c < TT_COST_INFEASIBLE && c > hi) hi = c;
    }
  if (!(lo < TT_COST_INFEASIBLE)) return NAN;
  return hi - lo;
}

/* Lowest cost among the vertices and the measured trial points: a reflection that beat
 * the best vertex counts while its expansion is pending. A trial never beats the best
 * vertex once its step is over (a better one becomes a vertex). */
double tt__nm_arm_best(const tt_tuner *t, const tt__nm_arm *a) {
  double b = INFINITY;
  for (size_t i = 0; i <= t->n + 3; i++)
    if (a->id[i] >= 0) {
      double c = tt__nm_cost(t, a, i);
      if (c < b) b = c;
    }
  return b;
}

double tt__nm_arm_optimistic(const tt_tuner *t, const tt__nm_arm *a) {
  /* The spread f_worst - f_best of a simplex is what the arm may still gain in cost units:
   * large while it explores, near zero once it has converged, so a converged arm yields
   * to one that is slightly worse but still moving. Failed measurements are left out. */
  double lo = tt__nm_arm_best(t, a), hi = -INFINITY;
  for (size_t i = 0; i <= t->n; i++)
    if (a->id[i] >= 0) {
      double c = tt__nm_cost(t, a, i);
      if (c < TT_COST_INFEASIBLE && c > hi) hi = c;
    }
  if (!(lo < TT_COST_INFEASIBLE)) return lo;
  return lo - (hi - lo);
}
