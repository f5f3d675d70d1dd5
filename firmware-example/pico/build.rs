//! The Pico firmware's build (`../hw/build_board.rs`, shared by the real boards): the RP2040
//! memory map (`memory.x`, with the 256-byte boot2 region), then the clip and the figure by the
//! QEMU firmware's own build code (`../build_common.rs`) and the servo output (`MOCAP_SERVO`).
//!
//! Link arguments: `--nmagic` (no page alignment of the sections: flash starts right after
//! boot2) and `-Tdefmt.x` (defmt's table of interned log strings, which stays in the ELF for
//! probe-rs to decode).

#[path = "../hw/build_board.rs"]
mod build_board;
#[path = "../build_common.rs"]
mod build_common;

fn main() {
    build_board::build(
        "mocap-firmware-pico",
        "thumbv6m-none-eabi",
        &["--nmagic", "-Tdefmt.x"],
    );
}
