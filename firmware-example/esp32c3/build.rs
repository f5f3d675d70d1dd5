//! The ESP32-C3 firmware's build (`../hw/build_board.rs`, shared by the real boards): no memory
//! map of its own (esp-hal's build script puts the chip's `memory.x` and `linkall.x` on the
//! linker's search path), then the clip and the figure by the QEMU firmware's own build code
//! (`../build_common.rs`) and the servo output (`MOCAP_SERVO`).
//!
//! Link arguments: `-Tlinkall.x` (esp-hal's link script: the memory map, the sections and the
//! `.flash.appdesc` section that holds the application descriptor the ESP-IDF bootloader
//! checks) and `-Tdefmt.x` (defmt's table of interned log strings, which stays in the ELF for
//! probe-rs to decode).

#[path = "../hw/build_board.rs"]
mod build_board;
#[path = "../build_common.rs"]
mod build_common;

fn main() {
    build_board::build_with_hal_link_script(
        "mocap-firmware-esp32c3",
        "riscv32imc-unknown-none-elf",
        &["-Tlinkall.x", "-Tdefmt.x"],
    );
}
