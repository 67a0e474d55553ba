/* Model files of the predictor plugins (predictor_nn, predictor_rbf): one container format,
 * written once here.
 *
 *   offset 0   "TTPMODEL"                    magic, 8 bytes
 *          8   u32 format version           (newer than the reader's: refused)
 *         12   u32 0                         reserved
 *         16   u64 payload bytes
 *         24   payload
 *   24+n       u64 FNV-1a 64 of bytes [0, 24+n)   (corruption)
 *
 * All numbers little-endian; doubles as their IEEE-754 bits, so save/load is bit-exact.
 * The payload starts with a common header (model kind, plugin version, state space, state
 * dimension and names, target-space signature, settings JSON), then the model's own fields.
 * Reading checks every length against what is left, so a cut-short or corrupt file is an
 * error naming the file and what was expected, never a crash. Saving writes a temporary file
 * in the same folder, fsyncs it and renames it over the target: a failed save leaves the old
 * file as it was.
 */
#ifndef TT_PREDICTOR_MODEL_FILE_H
#define TT_PREDICTOR_MODEL_FILE_H

#include <tunetrace/params.h>

#include <stddef.h>
#include <stdint.h>

#define TT__PM_MAGIC "TTPMODEL"
#define TT__PM_HEADER_BYTES 24u

/* A growing output buffer; `failed` sticks after the first allocation failure. */
typedef struct tt__pm_writer {
  unsigned char *data;
  size_t len, cap;
  int failed;
} tt__pm_writer;

void tt__pm_put_u32(tt__pm_writer *w, uint32_t v);
void tt__pm_put_u64(tt__pm_writer *w, uint64_t v);
void tt__pm_put_f64(tt__pm_writer *w, double v);
void tt__pm_put_f64s(tt__pm_writer *w, const double *v, size_t n);
void tt__pm_put_str(tt__pm_writer *w, const char *s); /* u32 length + bytes; NULL as "" */

/* A bounds-checked cursor over a payload; the first error is kept in `err` (a message
 * naming the file and the offset), later reads return zeros. */
typedef struct tt__pm_reader {
  const unsigned char *data;
  size_t len, pos;
  const char *path;
  char err[512];
} tt__pm_reader;

uint32_t tt__pm_get_u32(tt__pm_reader *r, const char *what);
uint64_t tt__pm_get_u64(tt__pm_reader *r, const char *what);
double tt__pm_get_f64(tt__pm_reader *r, const char *what);
void tt__pm_get_f64s(tt__pm_reader *r, double *v, size_t n, const char *what);
/* A string of at most `max` bytes as a malloc'ed NUL-terminated copy (NULL on error). */
char *tt__pm_get_str(tt__pm_reader *r, size_t max, const char *what);
/* A count that must be <= max and fit `elem` bytes per item in what is left. */
uint64_t tt__pm_get_count(tt__pm_reader *r, uint64_t max, size_t elem, const char *what);
/* Records an error (first one wins). */
void tt__pm_fail(tt__pm_reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The fields every model file begins with. */
typedef struct tt__pm_header {
  char *kind;           /* plugin name: "predictor_nn", "predictor_rbf" */
  char *plugin_version; /* the plugin version that wrote it */
  char *state_space;    /* tt_predictor_setup.state_space */
  uint32_t state_dim;
  char **state_names; /* state_dim names, or NULL */
  char *target;       /* target-space signature (tt__pm_space_signature) */
  char *settings;     /* the model's hyper-parameters as configuration JSON */
} tt__pm_header;

void tt__pm_header_free(tt__pm_header *h);
void tt__pm_put_header(tt__pm_writer *w, const tt__pm_header *h);
/* Reads the header; 0, or -1 with r->err set. */
int tt__pm_get_header(tt__pm_reader *r, tt__pm_header *h);

/* One-line description of a space's parameters (names, types, ranges, possible values):
 * "accel_embree: quality NOM{1,2,3}; maxDepth INT[8,64]; travcost FLOAT[0.1,10] log; ...".
 * Two spaces whose signatures are equal have the same configurations. malloc'ed. */
char *tt__pm_space_signature(const tt_space *space);
/* The first parameter where two signatures differ, as "A vs B" (or the whole lengths), into
 * buf. */
void tt__pm_signature_diff(const char *a, const char *b, char *buf, size_t n);

/* Configurations as one double per parameter: INT/FLOAT the value, NOM the index. Exact
 * both ways (FLOAT values are stored, not their unit-cube image). */
void tt__pm_config_values(const tt_config *c, double *out);
/* 0, or -1 if a value is not valid for the space (message in why). */
int tt__pm_config_from_values(tt_config *c, const double *v, char *why, size_t n);

/* Writes magic + version + payload + checksum to `path` atomically. TT_OK or TT_ERR_IO
 * with a message naming `who` and the file. */
tt_status tt__pm_save(const char *who, const char *path, uint32_t version, const tt__pm_writer *w);

/* Reads `path`: checks magic, version (<= max_version), length and checksum, and returns the
 * payload (malloc'ed, *payload_len) and the file's version. Errors name `who`, the file and
 * what is wrong. */
tt_status tt__pm_load(const char *who, const char *who_version, const char *path,
                      uint32_t max_version, unsigned char **payload, size_t *payload_len,
                      uint32_t *version);

#endif /* TT_PREDICTOR_MODEL_FILE_H */
