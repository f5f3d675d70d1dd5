//! The Black Pill firmware's build (`../hw/build_board.rs`, shared by the real boards): the
//! STM32F411CE memory map, then the clip and the figure by the QEMU firmware's own build code
//! (`../build_common.rs`) and the servo output (`MOCAP_SERVO`). Link argument: `-Tdefmt.x`
//! (defmt's table of interned log strings, which stays in the ELF for probe-rs to decode).

#[path = "../hw/build_board.rs"]
mod build_board;
#[path = "../build_common.rs"]
mod build_common;

fn main() {
    build_board::build(
        "mocap-firmware-blackpill",
        "thumbv7em-none-eabihf",
        &["-Tdefmt.x"],
    );
}
