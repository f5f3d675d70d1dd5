#!/usr/bin/env bash
# Fuzz the decoder (decoder-nostd/fuzz, cargo-fuzz + libFuzzer): every target in
# decoder-nostd/fuzz/fuzz_targets/ for SECONDS each —
#   parse_and_play  any bytes -> Clip::parse + every way of playing: an Err or values, no panic;
#   readers         any bytes -> the BVH, ASF, ASF + AMC and C3D readers: a motion or a located error;
#   roundtrip       arbitrary small motion -> encoder -> decoder: every value within the bound;
#   entropy         any bytes -> the rANS table parser + decoder (SPEC.md §10): an Err or symbols in
#                   the alphabet; decoded symbols re-encode and decode back.
#
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]   # default 120 s per target, all targets
#   bash scripts/fuzz.sh --smoke                 # 30 s per target (scripts/test.sh runs this)
#
# Needs a nightly toolchain (`cargo +nightly`) and cargo-fuzz (`cargo install cargo-fuzz`); without
# them it prints `fuzz smoke: skipped (no nightly/cargo-fuzz)` and exits 0. The parse_and_play
# corpus (decoder-nostd/fuzz/corpus/, not committed: the fuzzer grows it) is seeded with real
# clips, so the fuzzer starts from valid files: the shipped demo, every codec and a servo clip
# of the demo and, when present, clips encoded from the CMU corpus. Prints the executions and
# coverage of each target from libFuzzer's output; a crash prints libFuzzer's report and the
# input it saved (decoder-nostd/fuzz/artifacts/). The roundtrip corpus starts from the minimised
# corpus of the long runs, committed as decoder-nostd/fuzz/seeds/roundtrip.tar.gz. Logs:
# target/fuzz/. The last line is `fuzz smoke: N passed, N failed` (or `fuzz: ...` outside --smoke).
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"

label=fuzz
secs=120
targets=()
for arg in "$@"; do
    case "$arg" in
        --smoke) label="fuzz smoke"; secs=30 ;;
        -h|--help) sed -n '2,/^$/p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        [0-9]*) secs="$arg" ;;
        *) targets+=("$arg") ;;
    esac
done
[ "${#targets[@]}" -gt 0 ] || mapfile -t targets < <(find decoder-nostd/fuzz/fuzz_targets -name '*.rs' -printf '%f\n' | sed 's/\.rs$//' | sort)

if ! cargo +nightly --version >/dev/null 2>&1 || ! cargo fuzz --version >/dev/null 2>&1; then
    echo "$label: skipped (no nightly/cargo-fuzz): install with rustup toolchain install nightly; cargo install cargo-fuzz"
    exit 0
fi

logs=target/fuzz
mkdir -p "$logs"
log="$logs/seeds.log"
: >"$log"
mocap_explain_failure fuzz.sh "$log"

# ---- seeds for parse_and_play
seeds=decoder-nostd/fuzz/corpus/parse_and_play
mkdir -p "$seeds"
cp firmware-example/clips/demo.mcb "$seeds/demo.mcb"
mocap_logged "$log" cargo build --release -q -p mocap-cli
mocap=target/release/mocap
encode() { mocap_logged "$log" "$mocap" encode "$@"; }
corpus="${MOCAP_CORPUS:-../shared/data}"
for f in "$corpus"/cmu/35_17.bvh "$corpus"/cmu/09_01.bvh; do
    [ -f "$f" ] || continue
    for k in 0 8; do
        encode "$f" -o "$seeds/$(basename "$f" .bvh)_k$k.mcb" --key-interval "$k"
    done
    # pca-spline: segments, blends, patches.
    encode "$f" -o "$seeds/$(basename "$f" .bvh)_pca.mcb" --codec pca-spline --max-error 50mm
done
encode assets/animatronic_demo.bvh -o "$seeds/demo_pca.mcb" --codec pca-spline
# predictive: blocks, range-coded residuals (short blocks: many restarts).
encode assets/animatronic_demo.bvh -o "$seeds/demo_pred.mcb" --codec predictive \
    --max-error 0.5deg --key-interval 16
# Servo clips (rig table).
encode assets/animatronic_demo.bvh --rig assets/rigs/animatronic_demo.toml \
    -o "$seeds/demo_servo.mcb" --codec pca-spline --max-error 1deg
encode assets/animatronic_demo.bvh --rig assets/rigs/animatronic_demo.toml \
    -o "$seeds/demo_servo_pred.mcb" --codec predictive --max-error 0.5deg

# Marker clips (the missing-sample section 0x81) and re-based index clips (SPEC §4.5).
for f in "$corpus"/c3d/*.c3d; do
    [ -f "$f" ] || continue
    encode "$f" -o "$seeds/$(basename "$f" .c3d)_markers.mcb" --max-error 20mm
    encode "$f" -o "$seeds/$(basename "$f" .c3d)_markers_idx.mcb" --codec index --max-error 20mm
done

# ---- seeds for readers: a selector byte (0 BVH, 1 ASF, 2 ASF NUL AMC, 3 C3D), then the file.
rseeds=decoder-nostd/fuzz/corpus/readers
mkdir -p "$rseeds"
{ printf '\x00'; cat assets/animatronic_demo.bvh; } >"$rseeds/demo.bvh"
if [ -f "$corpus/asf-amc/16.asf" ]; then
    { printf '\x01'; cat "$corpus/asf-amc/16.asf"; } >"$rseeds/16.asf"
    # A short AMC: the first 40 frames of 16_15 (the fuzzer's inputs stay small).
    { printf '\x02'; cat "$corpus/asf-amc/16.asf"; printf '\x00'; awk '/^[0-9]+$/ { n++ } n <= 40' "$corpus/asf-amc/16_15.amc"; } >"$rseeds/16_15.amc"
fi
for f in "$corpus"/c3d/*.c3d; do
    [ -f "$f" ] || continue
    { printf '\x03'; head -c 65536 "$f"; } >"$rseeds/$(basename "$f")"
done

# ---- seeds for roundtrip: the minimised corpus of the long runs (BENCHMARKS.md §4), committed as
# decoder-nostd/fuzz/seeds/roundtrip.tar.gz (2 929 arbitrary motions, 2026-12-03); files the
# fuzzer has added since stay.
mkdir -p decoder-nostd/fuzz/corpus
tar -xzf decoder-nostd/fuzz/seeds/roundtrip.tar.gz -C decoder-nostd/fuzz/corpus --keep-old-files 2>/dev/null || true

# ---- build, then run each target
cd decoder-nostd/fuzz
passed=0
failed=()
for t in "${targets[@]}"; do
    tlog="../../$logs/$t.log"
    : >"$tlog"
    # roundtrip runs the encoder's search on every input: without the comparison tracing of
    # every f64 loop (more than half its time in __sanitizer_cov_trace_cmp8, perf) it runs ~5×
    # faster (BENCHMARKS.md §4); parse_and_play keeps it (it guides the fuzzer through the
    # parsers' magic values).
    build_flags=()
    [ "$t" = roundtrip ] && build_flags=(--no-trace-compares)
    if ! mocap_logged "$tlog" cargo +nightly fuzz build "${build_flags[@]}" "$t"; then
        printf '%s: %s: FAILED to build (log: %s)\n' "$label" "$t" "$logs/$t.log"
        failed+=("$t")
        continue
    fi
    extra=()
    [ "$t" = parse_and_play ] && extra=(-max_len=65536)
    [ "$t" = readers ] && extra=(-max_len=131072)
    rc=0
    cargo +nightly fuzz run "${build_flags[@]}" "$t" -- -max_total_time="$secs" "${extra[@]}" >>"$tlog" 2>&1 || rc=$?
    # libFuzzer: "#N DONE cov: C ft: F corp: K/S ..." and "Done N runs in S second(s)".
    stats="$(grep -E '^#[0-9]+' "$tlog" | tail -n1 | sed -E 's/^#([0-9]+)[[:space:]]+[A-Z]+[[:space:]]+/\1 /')"
    execs="${stats%% *}"
    cov="$(sed -nE 's/.*cov: ([0-9]+).*/\1/p' <<<"$stats")"
    ft="$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$stats")"
    corp="$(sed -nE 's/.* corp: ([0-9]+\/[0-9A-Za-z]+).*/\1/p' <<<"$stats")"
    if [ "$rc" -eq 0 ]; then
        printf '%s: %s: ok, %s executions in %s s, coverage %s edges, %s features, corpus %s\n' \
            "$label" "$t" "${execs:-?}" "$secs" "${cov:-?}" "${ft:-?}" "${corp:-?}"
        passed=$((passed + 1))
    else
        printf '%s: %s: FAILED (exit %s) after %s executions; libFuzzer says (log: %s):\n' \
            "$label" "$t" "$rc" "${execs:-?}" "$logs/$t.log"
        grep -E -A 30 '^(==[0-9]+==|thread .* panicked|SUMMARY:|ERROR:)' "$tlog" | head -n 40 | sed 's/^/    /'
        grep -E 'Test unit written to|artifact_prefix' "$tlog" | sed 's/^/    /'
        failed+=("$t")
    fi
done
echo "$label: $passed passed, ${#failed[@]} failed"
[ "${#failed[@]}" -eq 0 ]
