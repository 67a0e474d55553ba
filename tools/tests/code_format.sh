#!/bin/bash
# Every tracked C/C++ source follows .clang-format (clang-format 14, Debian clang-format-14):
# one layout for the whole tree, so a change's diff holds its change and not a re-layout.
# Fix a failure with: clang-format-14 -i FILE (or `git clang-format-14 main` before committing).
set -euo pipefail
cd "$(dirname "$0")/../.."
cf=$(command -v clang-format-14 || true)
if [ -z "$cf" ]; then
  echo "code_format: clang-format-14 not found (tools/bootstrap.sh installs it)" >&2
  exit 1
fi
mapfile -t files < <(git ls-files '*.c' '*.h' '*.cpp' '*.hpp' 2>/dev/null || true)
if [ "${#files[@]}" -eq 0 ]; then
  # Not a git checkout (a source tarball): list the sources the same way.
  mapfile -t files < <(find core host mpi plugins python tests tools examples \
    \( -name '*.c' -o -name '*.h' -o -name '*.cpp' -o -name '*.hpp' \) -type f | sort)
fi
[ "${#files[@]}" -ge 100 ] || { echo "code_format: only ${#files[@]} sources found" >&2; exit 1; }
bad=()
for f in "${files[@]}"; do
  if ! "$cf" --dry-run --Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done
echo "code_format: ${#files[@]} sources checked, ${#bad[@]} not following .clang-format"
if [ "${#bad[@]}" -gt 0 ]; then
  printf '  %s\n' "${bad[@]}"
  echo "fix: clang-format-14 -i ${bad[*]}" >&2
  exit 1
fi
