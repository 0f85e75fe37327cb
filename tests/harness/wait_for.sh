# Bounded waits for shell-level integration tests (source this file).
# wait_for_file PATH SECONDS: returns 1 (and says so) if PATH never appears.
wait_for_file() {
  local path=$1 limit=$2 i
  for ((i = 0; i < limit * 20; i++)); do
    [ -e "$path" ] && return 0
    sleep 0.05
  done
  echo "timed out after ${limit}s waiting for $path" >&2
  return 1
}
# wait_for_line FILE PATTERN SECONDS: waits until FILE has a line matching PATTERN.
wait_for_line() {
  local file=$1 pattern=$2 limit=$3 i
  for ((i = 0; i < limit * 20; i++)); do
    grep -qE "$pattern" "$file" 2>/dev/null && return 0
    sleep 0.05
  done
  echo "timed out after ${limit}s waiting for '$pattern' in $file" >&2
  return 1
}
