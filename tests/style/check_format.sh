#!/usr/bin/env bash
# Fails naming every C++ file that clang-format would change, and says how
# to fix them all. Files come from git where the tree is a clone.
set -euo pipefail
cd "${IVOA_SOURCE_DIR:?}"
command -v clang-format >/dev/null || { echo "clang-format not installed: skipped"; exit 77; }

if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
else
  mapfile -t files < <(find libs processes drivers tools tests -name '*.cpp' -o -name '*.hpp' | sort)
fi
unformatted=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue  # deleted but not yet committed
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || unformatted+=("$f")
done
echo "checked ${#files[@]} files with $(clang-format --version)"
if [ ${#unformatted[@]} -gt 0 ]; then
  printf 'not formatted by .clang-format: %s\n' "${unformatted[@]}"
  echo "fix: clang-format -i ${unformatted[*]}"
  exit 1
fi
