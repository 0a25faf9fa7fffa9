#!/usr/bin/env bash
# Text a user reads carries no history of how it was made: README.md, docs/ (NEWS.md and notes/
# are the history, and excepted), src/ and the --help of epa and of every subcommand it lists
# (and theirs in turn) name no "issue N", no date (YYYY-MM-DD), not "this machine" or "this VM",
# no ../shared path, and no *.md document that the repository does not have. Each finding is one
# line, file:line: what, and the test fails if there is any.
# Usage: no_history_test.sh EPA_BINARY SOURCE_DIR
set -uo pipefail
epa=$1
src=$2
cd "$src" || exit 2

findings=0
report() { findings=$((findings + 1)); echo "FOUND: $*"; }

# The documents the repository has, by file name (a reference may give a path or the name alone).
known_md=$(find . -path ./build -prune -o -path ./.git -prune -o -name '*.md' -print | sed 's|.*/||' | sort -u)

# check WHERE: reads text on stdin, one finding per offending line, named WHERE:LINE.
check() {
  local where=$1 n=0 line lower name
  while IFS= read -r line || [ -n "$line" ]; do
    n=$((n + 1))
    lower=${line,,}
    [[ $lower =~ (^|[^a-z])(issue[[:space:]]+#?[0-9]+) ]] && report "$where:$n: names an issue (\"${BASH_REMATCH[2]}\"): $line"
    [[ $line =~ (^|[^0-9])([0-9]{4}-[01][0-9]-[0-3][0-9])([^0-9]|$) ]] && report "$where:$n: a date (${BASH_REMATCH[2]}): $line"
    [[ $lower == *"this machine"* ]] && report "$where:$n: \"this machine\": $line"
    [[ $lower =~ this[[:space:]]vm([^a-z]|$) ]] && report "$where:$n: \"this VM\": $line"
    [[ $line == *"../shared"* ]] && report "$where:$n: a ../shared path: $line"
    local rest=$line named=" "
    while [[ $rest =~ ([A-Za-z0-9_./-]*[A-Za-z0-9_-]\.md)([^A-Za-z0-9_]|$) ]]; do
      name=${BASH_REMATCH[1]##*/}
      rest=${rest#*"${BASH_REMATCH[1]}"}
      [[ $named == *" $name "* ]] && continue  # once per line
      named+="$name "
      grep -qxF -- "$name" <<<"$known_md" || report "$where:$n: names $name, which the repository does not have: $line"
    done
  done
  return 0
}

files=()
[ -f README.md ] && files+=(README.md)
while IFS= read -r f; do files+=("$f"); done < <(
  { find docs -type f \( -name '*.md' -o -name '*.txt' \) -not -name NEWS.md -not -path '*/notes/*' 2>/dev/null
    find src -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' -o -name '*.txt' -o -name '*.md' \) 2>/dev/null; } | sort)
for f in "${files[@]}"; do check "$f" <"$f"; done

# The --help of epa and of every subcommand its help lists, recursively (e.g. `epa tuning list`).
helps=0
help_of() {  # $@: the subcommand path
  local out
  if ! out=$("$epa" "$@" --help 2>&1); then
    report "epa $* --help: exits non-zero: $out"
    return
  fi
  helps=$((helps + 1))
  check "epa${*:+ $*} --help" <<<"$out"
  local sub
  [ $# -lt 3 ] || return 0  # epa's commands go two deep; a deeper list is not followed
  for sub in $(awk '/^Subcommands:/ {on = 1; next} on && /^[^ ]/ {on = 0} on && /^  [a-z]/ {print $1}' <<<"$out"); do
    help_of "$@" "$sub"
  done
}
help_of
if [ "$helps" -lt 2 ]; then
  echo "FAIL: epa --help listed no subcommand (read $helps help text): the check saw nothing"
  exit 1
fi

echo "read ${#files[@]} files and $helps help texts; $findings finding(s)"
[ "$findings" -eq 0 ] && echo "PASS" || { echo "FAIL: $findings finding(s) above"; exit 1; }
