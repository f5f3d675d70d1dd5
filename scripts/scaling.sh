#!/usr/bin/env bash
# Encode time and memory against clip length (issue 15, BENCHMARKS.md "Long inputs"): long
# inputs made by `mocap generate long` from a corpus take (each repetition continues the root's
# path and heading), encoded by every codec at 50mm+arms:10mm and at 1deg under
# `/usr/bin/time -v` (wall seconds, user+system CPU seconds, peak RSS). Prints a Markdown table.
#   bash scripts/scaling.sh                     # 01_14 and 35_01 at 1 000, 10 000, 100 000 frames
#   SCALING_FRAMES="1000 10000" SCALING_TAKES="cmu/35_01.bvh" SCALING_CODECS="pca-spline" \
#       SCALING_BOUNDS="1deg" bash scripts/scaling.sh
#   SCALING_TIMEOUT=3600 (seconds per encode; a row past it says so)
#   MOCAP=path/to/mocap (a binary to measure instead of building target/release/mocap)
# The inputs go to a temporary folder, removed at the end. Installs GNU time (package `time`)
# when /usr/bin/time is missing.
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
corpus="${MOCAP_CORPUS:-../shared/data}"
frames_list="${SCALING_FRAMES:-1000 10000 100000}"
takes="${SCALING_TAKES:-cmu-long/01_14.bvh cmu/35_01.bvh}"
codecs="${SCALING_CODECS:-index pca-spline predictive}"
bounds="${SCALING_BOUNDS:-50mm+arms:10mm 1deg}"
limit="${SCALING_TIMEOUT:-3600}"
[ -x /usr/bin/time ] || mocap_ensure_packages time
if [ -z "${MOCAP:-}" ]; then
    cargo build --release -q -p mocap-cli
fi
mocap="${MOCAP:-${CARGO_TARGET_DIR:-target}/release/mocap}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

echo "| take | frames | codec | bound | wall s | CPU s | peak RSS MB | bytes | ratio | result |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for take in $takes; do
    name="$(basename "$take" .bvh)"
    for n in $frames_list; do
        input="$tmp/${name}_$n.bvh"
        "$mocap" generate long --from "$corpus/$take" --skip 1 --frames "$n" -o "$input" 2>/dev/null
        for codec in $codecs; do
            for bound in $bounds; do
                out="$tmp/out.mcb"
                rm -f "$out"
                rc=0
                timeout "$limit" /usr/bin/time -v -o "$tmp/time.txt" \
                    "$mocap" encode "$input" -o "$out" --codec "$codec" --max-error "$bound" \
                    >"$tmp/stdout.txt" 2>"$tmp/stderr.txt" || rc=$?
                field() { sed -n "s/^\t$1: //p" "$tmp/time.txt" 2>/dev/null | head -1; }
                wall="$(field 'Elapsed (wall clock) time (h:mm:ss or m:ss)')"
                wall_s="$(echo "$wall" | awk -F: '{ s = 0; for (i = 1; i <= NF; i++) s = s * 60 + $i; printf "%.2f", s }')"
                cpu_s="$(awk -v u="$(field 'User time (seconds)')" -v s="$(field 'System time (seconds)')" 'BEGIN { printf "%.2f", u + s }')"
                rss_mb="$(awk -v k="$(field 'Maximum resident set size (kbytes)')" 'BEGIN { printf "%.0f", k / 1024 }')"
                if [ "$rc" -eq 0 ]; then
                    bytes="$(stat -c %s "$out")"
                    ratio="$(awk -v n="$n" -v b="$bytes" -v c="$(sed -n 's/.* × \([0-9]*\) channels.*/\1/p' "$tmp/stderr.txt" | head -1)" 'BEGIN { printf "%.1f", n * c * 4 / b }')"
                    result="ok"
                elif [ "$rc" -eq 124 ]; then
                    bytes="-"; ratio="-"; wall_s="> $limit"; cpu_s="-"; rss_mb="-"
                    result="stopped after ${limit} s"
                else
                    bytes="-"; ratio="-"
                    result="fails: $(grep 'mocap: error' "$tmp/stderr.txt" | head -1 | sed 's/^mocap: error: //; s/|/\\|/g')"
                fi
                echo "| $name | $n | $codec | $bound | $wall_s | $cpu_s | $rss_mb | $bytes | $ratio | $result |"
            done
        done
    done
done
