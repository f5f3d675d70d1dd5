#!/usr/bin/env bash
# The bytes the encoder writes for the corpus, as sha256 lines: every file of cmu, cmu-long and
# iclone-cmu encoded with each codec (index, pca-spline, predictive) at 1deg and 50mm+arms:10mm.
# Run it with two binaries (before and after a change) and diff the outputs: a change that should
# not move the bytes must leave every line as it was (issue 15's identity proof).
#   bash scripts/corpus_sha.sh [MOCAP_BINARY] > sums.txt   (default: target/release/mocap)
#   Each line: sha256, file, codec, bound, then the encode's wall seconds after a '#'.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mocap="${1:-${CARGO_TARGET_DIR:-target}/release/mocap}"
corpus="${MOCAP_CORPUS:-../shared/data}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
for dir in cmu cmu-long iclone-cmu; do
    for f in "$corpus/$dir"/*.bvh; do
        for codec in index pca-spline predictive; do
            for bound in 1deg 50mm+arms:10mm; do
                out="$tmp/out.mcb"
                start=$(date +%s.%N)
                if "$mocap" encode "$f" -o "$out" --codec "$codec" --max-error "$bound" \
                    >/dev/null 2>"$tmp/err"; then
                    sum=$(sha256sum "$out" | cut -d' ' -f1)
                else
                    sum="FAILED:$(tail -1 "$tmp/err")"
                fi
                end=$(date +%s.%N)
                printf '%s %s/%s %s %s # %.2f s\n' "$sum" "$dir" "$(basename "$f")" "$codec" \
                    "$bound" "$(echo "$end - $start" | bc)"
            done
        done
    done
done
