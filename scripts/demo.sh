#!/usr/bin/env bash
# The main job on the clip the project ships: encode the procedural
# animatronic demo (assets/animatronic_demo.bvh) for an MCU at 1°, show what
# is inside, measure it, then play it on an emulated Cortex-M3 in QEMU and
# check the firmware's output against the host decoder.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/toolchain.sh
source scripts/toolchain.sh
mocap_toolchain_setup >&2

cargo build --release -q -p mocap-encoder
mocap=target/release/mocap
out=target/demo
mkdir -p "$out"
"$mocap" encode --target mcu --codec index --max-error 1deg assets/animatronic_demo.bvh -o "$out/demo.mcb"
"$mocap" info "$out/demo.mcb"
"$mocap" eval assets/animatronic_demo.bvh "$out/demo.mcb"
"$mocap" decode "$out/demo.mcb" -o "$out/demo_decoded.bvh"
"$mocap" decode --text "$out/demo.mcb" -o "$out/host.txt"
echo "playing on Cortex-M3 (QEMU lm3s6965evb)…" >&2
bash scripts/firmware.sh run --board lm3s6965 --clip "$out/demo.mcb" --icount >"$out/uart.txt"
grep '^#' "$out/uart.txt"
if grep -v '^#' "$out/uart.txt" | cmp -s - "$out/host.txt"; then
    echo "firmware output identical to the host decoder ($(grep -vc '^#' "$out/uart.txt") frames)"
else
    echo "firmware output DIFFERS from the host decoder" >&2
    exit 1
fi
