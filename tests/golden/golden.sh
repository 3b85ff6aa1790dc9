#!/usr/bin/env bash
# Golden replay files (tests/golden/cases.txt describes them).
#
#   golden.sh check-output USV_FDI CASE [WORK_DIR]  replay CASE.csv, diff against CASE.jsonl
#   golden.sh check-input  USV_FDI CASE [WORK_DIR]  re-simulate CASE.csv, diff against it
#   golden.sh update       USV_FDI [--outputs-only] regenerate every CASE.csv and CASE.jsonl
#   golden.sh list                                  print the case names
#
# USV_FDI is the usv-fdi executable. Runs from the repository root (configs are relative to
# it). Needs bash, awk and diff only. Exit status: 0 equal, 1 different, 2 usage or error.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
cases="$here/cases.txt"
cd "$root"

die() {
  echo "golden: $*" >&2
  exit 2
}

trim() {
  local s="$1"
  s="${s#"${s%%[![:space:]]*}"}"
  s="${s%"${s##*[![:space:]]}"}"
  printf '%s' "$s"
}

case_names() {
  local name rest
  while IFS='|' read -r name rest; do
    name="$(trim "$name")"
    [[ -z "$name" || "$name" == \#* ]] && continue
    printf '%s\n' "$name"
  done <"$cases"
}

# read_case NAME: sets CONFIG, REPLAY_OPTS (array), SIM_OPTS (array).
read_case() {
  local want="$1" name config replay sim
  while IFS='|' read -r name config replay sim; do
    name="$(trim "$name")"
    [[ -z "$name" || "$name" == \#* ]] && continue
    if [[ "$name" == "$want" ]]; then
      CONFIG="$(trim "$config")"
      read -ra REPLAY_OPTS <<<"$replay"
      read -ra SIM_OPTS <<<"$sim"
      [[ -n "$CONFIG" && ${#SIM_OPTS[@]} -gt 0 ]] || die "$cases: case '$want' needs a config and sim options"
      [[ -f "$CONFIG" ]] || die "$cases: case '$want': config '$CONFIG' does not exist"
      return 0
    fi
  done <"$cases"
  die "$cases: no case named '$want'"
}

# Keeps t,v,r,delta (rounded to 9 significant digits; nan/inf untouched) and the fault
# columns of the simulator's CSV.
shrink_csv() {
  awk 'BEGIN { FS = OFS = ","; n = split("t,v,r,delta,fault_a,fault_g", want, ",") }
    NR == 1 {
      for (i = 1; i <= NF; i++) idx[$i] = i
      for (j = 1; j <= n; j++) {
        if (!(want[j] in idx)) { print "golden: simulator CSV has no column " want[j] > "/dev/stderr"; exit 2 }
        col[j] = idx[want[j]]
      }
      print "t,v,r,delta,fault_a,fault_g"
      next
    }
    {
      line = ""
      for (j = 1; j <= n; j++) {
        x = $(col[j])
        if (j <= 4 && x ~ /^[-+]?[0-9.]/) x = sprintf("%.9g", x + 0)
        line = line (j > 1 ? "," : "") x
      }
      print line
    }'
}

# make_input USV_FDI CASE OUT.csv
make_input() {
  local exe="$1" name="$2" out="$3" raw
  read_case "$name"
  raw="$(mktemp)"
  if ! "$exe" --log-level warn sim "${SIM_OPTS[@]}" --output "$raw"; then
    rm -f "$raw"
    die "usv-fdi sim failed for case '$name'"
  fi
  shrink_csv <"$raw" >"$out"
  rm -f "$raw"
}

# make_output USV_FDI CASE IN.csv OUT.jsonl
make_output() {
  local exe="$1" name="$2" in="$3" out="$4"
  read_case "$name"
  "$exe" --log-level warn replay --config "$CONFIG" --input "$in" --output "$out" \
    "${REPLAY_OPTS[@]}" || die "usv-fdi replay failed for case '$name'"
}

# One JSON field per line, so that a diff names the fields that changed; each record starts
# with a line of its type and time, which the diff shows in every hunk header.
explode() {
  awk '{
    n = split($0, f, /,"/)
    print f[1] (n > 1 ? ",\"" f[2] : "")
    for (i = 3; i <= n; i++) print "  \"" f[i]
  }' "$1"
}

report_diff() {
  local what="$1" want="$2" got="$3" kind="$4"
  local changed total
  changed="$(diff "$want" "$got" | grep -c '^>' || true)"
  total="$(wc -l <"$want")"
  echo "golden: $what differs from ${want#"$root"/}: $changed of $total lines changed"
  echo "        (actual output kept in $got)"
  if [[ "$kind" == jsonl ]]; then
    diff -U2 -F '^[{]' --label "expected ${want#"$root"/}" --label "actual" <(explode "$want") <(explode "$got") |
      head -n 200 || true
  else
    diff -U1 --label "expected ${want#"$root"/}" --label "actual" "$want" "$got" | head -n 120 || true
  fi
  echo "golden: if this change is intended, run ./scripts/update-golden.sh and commit the"
  echo "        regenerated tests/golden files with the change that caused it."
}

usage() { sed -n '2,10p' "${BASH_SOURCE[0]}" >&2; exit 2; }

cmd="${1:-}"
case "$cmd" in
  list)
    case_names
    ;;
  check-output | check-input)
    [[ $# -ge 3 ]] || usage
    exe="$2"
    name="$3"
    work="${4:-$(mktemp -d)}"
    mkdir -p "$work"
    [[ -x "$exe" ]] || die "not an executable: $exe"
    if [[ "$cmd" == check-output ]]; then
      want="$here/$name.jsonl"
      got="$work/$name.jsonl"
      [[ -f "$want" && -f "$here/$name.csv" ]] || die "missing $want or its CSV; run ./scripts/update-golden.sh"
      make_output "$exe" "$name" "$here/$name.csv" "$got"
      kind=jsonl
      what="the replay of tests/golden/$name.csv"
    else
      want="$here/$name.csv"
      got="$work/$name.csv"
      [[ -f "$want" ]] || die "missing $want; run ./scripts/update-golden.sh"
      make_input "$exe" "$name" "$got"
      kind=csv
      what="the simulator's output for case $name"
    fi
    if cmp -s "$want" "$got"; then
      echo "golden: $name: $(wc -l <"$want") lines identical to ${want#"$root"/}"
      exit 0
    fi
    report_diff "$what" "$want" "$got" "$kind"
    exit 1
    ;;
  update)
    [[ $# -ge 2 ]] || usage
    exe="$2"
    outputs_only=0
    [[ "${3:-}" == "--outputs-only" ]] && outputs_only=1
    [[ -x "$exe" ]] || die "not an executable: $exe"
    total=0
    while read -r name; do
      if [[ $outputs_only -eq 0 ]]; then
        make_input "$exe" "$name" "$here/$name.csv"
      fi
      [[ -f "$here/$name.csv" ]] || die "missing $here/$name.csv (run without --outputs-only)"
      make_output "$exe" "$name" "$here/$name.csv" "$here/$name.jsonl"
      for f in "$here/$name.csv" "$here/$name.jsonl"; do
        size=$(wc -c <"$f")
        total=$((total + size))
        printf 'golden: %-40s %8d bytes\n' "${f#"$root"/}" "$size"
      done
    done < <(case_names)
    printf 'golden: %-40s %8d bytes\n' "total" "$total"
    ;;
  *)
    usage
    ;;
esac
