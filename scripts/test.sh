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

# The decoder must build for every Cortex-M target on its own too (no_std,
# no allocation), not only inside the firmware.
cargo test --release --workspace
