/* The limits of user-given numbers (tunetrace/limits.h): values at the ends of each range
 * accepted, one past refused, numbers wider than 32 or 64 bits refused (never wrapped), signs,
 * spaces and trailing text refused, the messages the host and Python print, and the names
 * bindings look the limits up by. */
#include <tunetrace/limits.h>

#include "tt_test.h"

/* tt_limit_parse_uint succeeds with `want`. */
static int uint_ok(tt_limit which, const char *text, uint64_t want) {
  uint64_t v = 0;
  return tt_limit_parse_uint(which, text, &v) == TT_OK && v == want;
}

/* tt_limit_parse_uint refuses `text`, leaving the output alone. */
static int uint_refused(tt_limit which, const char *text) {
  uint64_t v = 12345;
  return tt_limit_parse_uint(which, text, &v) == TT_ERR_INVALID_ARGUMENT && v == 12345;
}

static void test_uint(void) {
  CHECK(uint_ok(TT_LIMIT_SPP, "1", 1));
  CHECK(uint_ok(TT_LIMIT_SPP, "16777216", 16777216));
  CHECK(uint_refused(TT_LIMIT_SPP, "16777217"));
  CHECK(uint_refused(TT_LIMIT_SPP, "0"));
  CHECK(uint_refused(TT_LIMIT_SPP, "1099511627776")); /* 2^40 */
  CHECK(uint_refused(TT_LIMIT_SPP, "-1"));
  CHECK(uint_refused(TT_LIMIT_SPP, "+4"));
  CHECK(uint_refused(TT_LIMIT_SPP, " 4"));
  CHECK(uint_refused(TT_LIMIT_SPP, "4 "));
  CHECK(uint_refused(TT_LIMIT_SPP, "4.0"));
  CHECK(uint_refused(TT_LIMIT_SPP, ""));
  CHECK(uint_refused(TT_LIMIT_SPP, NULL));
  CHECK(uint_ok(TT_LIMIT_SEED, "0", 0));
  CHECK(uint_ok(TT_LIMIT_SEED, "18446744073709551615", UINT64_MAX));
  CHECK(uint_refused(TT_LIMIT_SEED, "18446744073709551616")); /* 2^64: ERANGE, not wrapped */
  CHECK(uint_refused(TT_LIMIT_SEED, "-1"));
  CHECK(uint_refused(TT_LIMIT_ITERATIONS, "4294967295")); /* -1 as uint32 */
  CHECK(uint_ok(TT_LIMIT_CAMERA_INDEX, "99", 99));
  CHECK(uint_refused(TT_LIMIT_CAMERA_INDEX, "100"));
  CHECK(uint_refused(TT_LIMIT_TIME, "5")); /* a real, not an integer */
  CHECK(tt_limit_parse_uint(TT_LIMIT_SPP, "0", &(uint64_t){0}) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "expected an integer in [1, 16777216], got \"0\"");
}

static void test_real(void) {
  double x = 0;
  CHECK(tt_limit_parse_real(TT_LIMIT_EPSILON, "0", &x) == TT_OK && x == 0);
  CHECK(tt_limit_parse_real(TT_LIMIT_EPSILON, "1", &x) == TT_OK && x == 1);
  CHECK(tt_limit_parse_real(TT_LIMIT_EPSILON, "1.0000001", &x) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), "the probability of exploring a state, a number in [0, 1]");
  CHECK(tt_limit_parse_real(TT_LIMIT_TIME, "0", &x) != TT_OK); /* open at 0 */
  CHECK(tt_limit_parse_real(TT_LIMIT_TIME, "1e7", &x) == TT_OK && x == 1e7);
  CHECK(tt_limit_parse_real(TT_LIMIT_TIME, "inf", &x) != TT_OK);
  CHECK(tt_limit_parse_real(TT_LIMIT_TIME, "nan", &x) != TT_OK);
  CHECK(tt_limit_parse_real(TT_LIMIT_TIME, "2s", &x) != TT_OK);
  CHECK(tt_limit_parse_real(TT_LIMIT_FPS, "1000", &x) == TT_OK && x == 1000);
  CHECK(tt_limit_parse_real(TT_LIMIT_FPS, "-24", &x) != TT_OK);
  CHECK(tt_limit_parse_real(TT_LIMIT_SPP, "4", &x) != TT_OK); /* an integer limit */
}

static void test_resolution(void) {
  uint32_t w = 0, h = 0;
  CHECK(tt_limit_parse_resolution("640x480", &w, &h) == TT_OK && w == 640 && h == 480);
  CHECK(tt_limit_parse_resolution("65536x1", &w, &h) == TT_OK && w == 65536 && h == 1);
  const char *bad[] = {"4294967304x8", "8x4294967297", "65537x1", "0x8", "8x0",    "8x", "x8", "8",
                       "8x8x",         "8x8 ",         "-8x8",    "8X8", "64by64", ""};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    w = h = 7;
    CHECK_MSG(tt_limit_parse_resolution(bad[i], &w, &h) == TT_ERR_INVALID_ARGUMENT && w == 7 &&
                  h == 7,
              "\"%s\" was accepted", bad[i]);
  }
  tt_limit_parse_resolution("4294967304x8", &w, &h);
  CHECK_CONTAINS(tt_last_error(), "expected WIDTHxHEIGHT (1..65536 each), got \"4294967304x8\"");
}

static void test_span(void) {
  uint64_t a = 7, b = 7;
  CHECK(tt_limit_parse_span(TT_LIMIT_FRAME, "0:4294967294", &a, &b) == TT_OK && a == 0 &&
        b == 4294967294u);
  CHECK(tt_limit_parse_span(TT_LIMIT_FRAME, "5:5", &a, &b) == TT_OK && a == 5 && b == 5);
  const char *bad[] = {
      "5:4", "0:4294967295", "4294967297:4294967298", "1:", ":1", "1", "1:2:3", "-1:2", "1:2 ", ""};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    a = b = 7;
    CHECK_MSG(tt_limit_parse_span(TT_LIMIT_FRAME, bad[i], &a, &b) == TT_ERR_INVALID_ARGUMENT &&
                  a == 7 && b == 7,
              "\"%s\" was accepted", bad[i]);
  }
  CHECK(tt_limit_parse_span(TT_LIMIT_CAMERA_INDEX, "3:100", &a, &b) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), "expected A:B with A <= B, each an integer in [0, 99]");
}

static void test_names(void) {
  tt_limit which;
  CHECK(tt_limit_find("spp", &which) == TT_OK && which == TT_LIMIT_SPP);
  CHECK(tt_limit_find("tune_spp", &which) == TT_OK && which == TT_LIMIT_TUNE_SPP);
  CHECK(tt_limit_find("warmup", &which) == TT_OK && which == TT_LIMIT_WARMUP);
  CHECK(tt_limit_find("spp ", &which) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_limit_find(NULL, &which) == TT_ERR_INVALID_ARGUMENT);
  double lo = 0, hi = 0;
  CHECK(tt_limit_range(TT_LIMIT_THREADS, &lo, &hi) == TT_OK && lo == 1 && hi == 1024);
  CHECK(tt_limit_range((tt_limit)999, &lo, &hi) == TT_ERR_INVALID_ARGUMENT);
}

int main(void) {
  test_uint();
  test_real();
  test_resolution();
  test_span();
  test_names();
  return tt_test_finish("limits_parse");
}
