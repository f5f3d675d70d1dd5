#!/usr/bin/env bash
# All the tests: installs what they need (QEMU, lld, the Cortex-M toolchain
# route), then runs every workspace test in release mode (unit tests, spec
# examples, corpus round trips, corruption, QEMU parity on M0/M3/M4F).
# The corpus is read from $MOCAP_CORPUS (default ../shared/data); without it
# the corpus tests print SKIPPED.
set -euo pipefail
cd "$(dirname "$0")/.."

# shellcheck source=scripts/toolchain.sh
source scripts/toolchain.sh
mocap_toolchain_setup
mocap_toolchain_summary >&2

export MOCAP_CORPUS="${MOCAP_CORPUS:-$(pwd)/../shared/data}"
[ -d "$MOCAP_CORPUS" ] || echo "SKIPPED: corpus not found at $MOCAP_CORPUS: corpus tests will be skipped" >&2

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
set +e
cargo test --release --workspace 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
set -e
grep -h '^SKIPPED' "$log" | sort -u || true
# One closing line for the whole run, summed over every test binary.
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i; if ($(i+1) ~ /^ignored/) s += $i } }
     END { printf "%d passed, %d failed, %d skipped\n", p, f, s }' "$log"
exit "$status"
