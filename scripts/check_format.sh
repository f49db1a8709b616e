#!/usr/bin/env bash
# The C++ lines changed since .clang-format came into the repository are laid out as it says (clang-format 14,
# Debian 12's). Older lines are left as they are: reformatting the whole tree at once would bury its history under
# one commit. Usage: check_format.sh [BASE] (default: the commit that added .clang-format). Exits 1 with the diff
# clang-format wants when a changed line differs, 0 when none does (and outside a git checkout, saying so).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v git-clang-format > /dev/null; then
  echo "check_format: git-clang-format is missing (Debian: apt-get install clang-format)" >&2
  exit 1
fi
if ! git rev-parse --is-inside-work-tree > /dev/null 2>&1; then
  echo "check_format: $(pwd) is not a git checkout: no changed lines to check"
  exit 0
fi
base=${1:-$(git log --diff-filter=A --format=%H -- .clang-format | tail -n 1)}
base=${base:-HEAD}  # .clang-format not committed yet: the lines changed since the last commit
if ! git rev-parse --verify --quiet "${base}^{commit}" > /dev/null; then
  echo "check_format: commit ${base} is not in this clone (a shallow one?): fetch its history" >&2
  exit 1
fi
out=$(git clang-format --binary clang-format --diff --extensions c,cc,cpp,cxx,h,hpp "$base" || true)
if [[ "$out" == diff* ]]; then
  echo "check_format: lines changed since ${base:0:12} differ from .clang-format's layout; apply with"
  echo "  git clang-format ${base:0:12}"
  echo "$out"
  exit 1
fi
echo "check_format: the C++ lines changed since ${base:0:12} follow .clang-format"
