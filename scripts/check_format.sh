#!/usr/bin/env bash
# The C++ lines changed since .clang-format came into the repository (its own commit included) are laid out as it says
# (clang-format 14, Debian 12's). Older lines are left as they are: reformatting the whole tree at once would bury its
# history under one commit. Usage: check_format.sh [BASE] (default: the parent of the commit that added .clang-format).
# Exits 0 when every changed line follows it (and, saying so, outside a git checkout: a source tarball), 1 with the
# diff clang-format wants when one does not, and 1 when it cannot tell (no git-clang-format, a shallow clone).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v git-clang-format > /dev/null; then
  echo "check_format: git-clang-format is missing (Debian: apt-get install clang-format)" >&2
  exit 1
fi
if [[ ! -e .git ]]; then
  echo "check_format: $(pwd) is not a git checkout: no changed lines to check"
  exit 0
fi
if ! git rev-parse --is-inside-work-tree > /dev/null; then  # git's own reason: dubious ownership, a damaged .git
  echo "check_format: git cannot read $(pwd)" >&2
  exit 1
fi
if [[ "$(git rev-parse --is-shallow-repository)" == true ]]; then
  echo "check_format: a shallow clone does not hold the commit .clang-format came in with: git fetch --unshallow" >&2
  exit 1
fi
if [[ $# -ge 1 ]]; then
  base=$1
else
  added=$(git log --diff-filter=A --format=%H -- .clang-format | tail -n 1)
  base=${added:+${added}^}
  base=${base:-HEAD}  # .clang-format not committed yet: the lines changed since the last commit
fi
status=0
out=$(git clang-format --binary clang-format --diff --extensions c,cc,cpp,cxx,h,hpp "$base") || status=$?
# git-clang-format 14 exits 0 whether or not it has a diff to show (its main()'s 1 is not passed on): the diff decides.
if [[ $status -eq 0 && "$out" == diff* ]]; then status=1; fi
case $status in
  0) echo "check_format: the C++ lines changed since $(git rev-parse --short "$base") follow .clang-format" ;;
  1)
    echo "check_format: lines changed since $(git rev-parse --short "$base") differ from .clang-format's layout;"
    echo "apply with: git clang-format $(git rev-parse --short "$base")"
    echo "$out"
    exit 1
    ;;
  *)
    echo "check_format: git clang-format failed (status $status): $out" >&2
    exit 1
    ;;
esac
