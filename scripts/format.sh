#!/usr/bin/env bash
# clang-format (.clang-format) over the project's C++ sources: every tracked
# .cc and .h file.
#   scripts/format.sh           formats them in place
#   scripts/format.sh --check   changes nothing; lists what is not formatted
#                               and exits 1 if anything is (CI runs this)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || {
  echo "format.sh: clang-format not found (apt-get install clang-format)" >&2
  exit 2
}
mapfile -t sources < <(git ls-files '*.cc' '*.h')
case "${1:-}" in
  "") clang-format -i "${sources[@]}" ;;
  --check)
    if ! clang-format --dry-run --Werror "${sources[@]}"; then
      echo "format.sh: the files above are not formatted (scripts/format.sh formats them)" >&2
      exit 1
    fi
    echo "format.sh: ${#sources[@]} files formatted" ;;
  *) echo "format.sh: unknown option '$1'" >&2; exit 2 ;;
esac
