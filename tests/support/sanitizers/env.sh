# Sanitizer run-time settings shared by tools/test_sanitized.sh (the unit and render suites
# of the ASan+UBSan build) and tests/fuzz/run.sh. Source it; it exports ASAN_OPTIONS,
# LSAN_OPTIONS, UBSAN_OPTIONS and the symbolizer. Leak checking is on; suppressions name
# third-party libraries only (README.md here says why each is there).
tt_san_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# detect_odr_violation=0: OpenImageIO and OpenColorIO both carry pystring/yaml symbols.
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1:detect_odr_violation=0${TT_ASAN_EXTRA:+:$TT_ASAN_EXTRA}"
# use_tls=0: LeakSanitizer itself crashed now and then scanning Embree's TBB worker threads'
# TLS (seen in #13); their allocations are reachable from the pools' globals anyway.
export LSAN_OPTIONS="suppressions=$tt_san_dir/lsan.supp:print_suppressions=0:use_tls=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$tt_san_dir/ubsan.supp"
if command -v llvm-symbolizer >/dev/null 2>&1; then
  export ASAN_SYMBOLIZER_PATH=$(command -v llvm-symbolizer)
fi
