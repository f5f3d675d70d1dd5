#!/usr/bin/env bash
# All the checks and tests, as CI runs them (.ci/run):
#  1. scripts/check.sh: fmt, clippy (workspace and firmware per board), the no_std builds, the
#     panic-machinery check of every board's firmware;
#  2. every workspace test in release mode (unit tests, spec examples, golden clips, corpus round
#     trips, corruption, QEMU parity on M0/M3/M4F);
#  3. a fuzz smoke (scripts/fuzz.sh --smoke: each target 30 s) when nightly and cargo-fuzz are
#     installed; it says so when they are not.
# It installs what the tests need first (QEMU, lld, the Cortex-M toolchain route, Chromium for the
# `mocap view` page tests). The corpus is read from $MOCAP_CORPUS (default ../shared/data); without
# it the corpus tests print `SKIPPED: <test>: <why>` and return, and without QEMU or Chromium the
# QEMU or browser tests do — except under CI (CI set), where they fail.
#
# The last line counts everything: `N passed, N failed, N skipped`, where a test that printed
# SKIPPED counts as skipped (not passed), as does an #[ignore]d test and a fuzz target that did not
# run; checks count one per step. Every part runs even when an earlier one failed; the exit code is
# non-zero if any failed. Logs: target/test/{check,test,fuzz}.log.
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
mocap_toolchain_setup
# The `mocap view` page tests open the page in headless Chromium (tests/tests/view_browser.rs);
# only the tests need it, not the firmware scripts.
mocap_ensure_packages chromium
mocap_toolchain_summary >&2

export MOCAP_CORPUS="${MOCAP_CORPUS:-$(pwd)/../shared/data}"
[ -d "$MOCAP_CORPUS" ] || echo "note: corpus not found at $MOCAP_CORPUS: the corpus tests will be skipped" >&2

logs=target/test
mkdir -p "$logs"
set +e
echo "== checks (scripts/check.sh)"
bash scripts/check.sh 2>&1 | tee "$logs/check.log"
check_status=${PIPESTATUS[0]}
echo "== tests (cargo test --release --workspace)"
cargo test --release --workspace 2>&1 | tee "$logs/test.log"
test_status=${PIPESTATUS[0]}
echo "== fuzz smoke (scripts/fuzz.sh --smoke)"
bash scripts/fuzz.sh --smoke 2>&1 | tee "$logs/fuzz.log"
fuzz_status=${PIPESTATUS[0]}
set -e

# Tests: libtest's counts, minus the tests that returned early with a SKIPPED line (distinct
# per test binary: cargo prints `Running ... (target/release/deps/<binary>-<hash>)` before each).
read -r t_pass t_fail t_ign t_skip <<<"$(awk '
    /^ *Running / { bin = $NF; gsub(/[()]/, "", bin); sub(/.*\//, "", bin); next }
    /^ *Doc-tests / { bin = "doc-" $2; next }
    /^SKIPPED: / { line = $0; sub(/^SKIPPED: /, "", line); name = line; sub(/: .*/, "", name); seen[bin " " name] = 1; next }
    /^test result:/ { for (i = 1; i < NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i; if ($(i+1) ~ /^ignored/) g += $i } }
    END { s = 0; for (k in seen) s++; printf "%d %d %d %d\n", p, f, g, s }' "$logs/test.log")"
if [ "$test_status" -ne 0 ] && [ "$t_fail" -eq 0 ]; then
    t_fail=1 # cargo failed before or outside a test (a build error): count it
fi
# Checks: check.sh's own closing line.
read -r c_pass c_fail <<<"$(sed -n 's/^checks: \([0-9]*\) passed, \([0-9]*\) failed$/\1 \2/p' "$logs/check.log" | tail -n1)"
if [ -z "${c_pass:-}" ]; then
    c_pass=0 c_fail=1 # check.sh died before its summary
fi
# Fuzz smoke: one per target.
f_targets=$(find decoder-nostd/fuzz/fuzz_targets -name '*.rs' | wc -l)
read -r f_pass f_fail <<<"$(sed -n 's/^fuzz smoke: \([0-9]*\) passed, \([0-9]*\) failed$/\1 \2/p' "$logs/fuzz.log" | tail -n1)"
f_skip=0
if [ -z "${f_pass:-}" ]; then
    if grep -q '^fuzz smoke: skipped' "$logs/fuzz.log"; then
        f_pass=0 f_fail=0 f_skip=$f_targets
    else
        f_pass=0 f_fail=1
    fi
fi

if [ "$t_skip" -gt 0 ]; then
    echo "skipped tests:"
    grep -h '^SKIPPED: ' "$logs/test.log" | sort -u | sed 's/^/  /'
fi
printf 'checks: %d passed, %d failed; tests: %d passed, %d failed, %d skipped (%d SKIPPED, %d ignored); fuzz smoke: %d passed, %d failed, %d skipped\n' \
    "$c_pass" "$c_fail" "$((t_pass - t_skip))" "$t_fail" "$((t_skip + t_ign))" "$t_skip" "$t_ign" "$f_pass" "$f_fail" "$f_skip"
# One closing line for the whole run.
printf '%d passed, %d failed, %d skipped\n' \
    "$((c_pass + t_pass - t_skip + f_pass))" "$((c_fail + t_fail + f_fail))" "$((t_skip + t_ign + f_skip))"
[ "$check_status" -eq 0 ] && [ "$test_status" -eq 0 ] && [ "$fuzz_status" -eq 0 ]
