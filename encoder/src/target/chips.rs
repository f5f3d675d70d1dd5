//! The chips `mocap encode --target` knows: core, clock, flash and RAM.

use std::fmt;

/// An instruction set and pipeline family: chips of one core run the same
/// decoder code, so the same instructions per pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Core {
    /// Cortex-M0 and M0+ (ARMv6-M, `thumbv6m-none-eabi`).
    M0,
    /// Cortex-M3 (ARMv7-M, `thumbv7m-none-eabi`).
    M3,
    /// Cortex-M4F (ARMv7E-M, `thumbv7em-none-eabihf`).
    M4F,
    /// RV32IMC (`riscv32imc-unknown-none-elf`).
    Rv32,
}

impl Core {
    /// Every core, in the order of the benchmark tables.
    pub const ALL: [Core; 4] = [Core::M0, Core::M3, Core::M4F, Core::Rv32];

    /// The name `scripts/boards.sh` and the measurement files use.
    pub fn name(self) -> &'static str {
        match self {
            Core::M0 => "M0",
            Core::M3 => "M3",
            Core::M4F => "M4F",
            Core::Rv32 => "RV32",
        }
    }

    /// The core named `s` (as [`Core::name`]).
    pub fn from_name(s: &str) -> Option<Core> {
        Core::ALL.into_iter().find(|c| c.name() == s)
    }
}

impl fmt::Display for Core {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A chip a clip can be made for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chip {
    /// `--target` value.
    pub name: &'static str,
    /// What it is (the part, the board users know it by).
    pub part: &'static str,
    pub core: Core,
    /// Core clock the budget's CPU share is taken of.
    pub clock_hz: u32,
    pub flash_bytes: u32,
    pub ram_bytes: u32,
}

const K: u32 = 1024;

/// Every chip, the QEMU boards of `scripts/boards.sh` first.
pub const CHIPS: &[Chip] = &[
    Chip {
        name: "microbit",
        part: "nRF51822 (BBC micro:bit v1; QEMU `microbit`)",
        core: Core::M0,
        clock_hz: 16_000_000,
        flash_bytes: 256 * K,
        ram_bytes: 16 * K,
    },
    Chip {
        name: "lm3s6965",
        part: "TI LM3S6965 (QEMU `lm3s6965evb`)",
        core: Core::M3,
        clock_hz: 50_000_000,
        flash_bytes: 256 * K,
        ram_bytes: 64 * K,
    },
    Chip {
        name: "mps2-an386",
        part: "Arm MPS2 AN386 FPGA image (QEMU `mps2-an386`)",
        core: Core::M4F,
        clock_hz: 25_000_000,
        flash_bytes: 4096 * K,
        ram_bytes: 4096 * K,
    },
    Chip {
        name: "riscv-virt",
        part: "QEMU `virt` RV32IMC (clock nominal: the machine has none)",
        core: Core::Rv32,
        clock_hz: 100_000_000,
        flash_bytes: 4096 * K,
        ram_bytes: 4096 * K,
    },
    Chip {
        name: "rp2040",
        part: "Raspberry Pi RP2040 (Pico; Cortex-M0+, 2 MB QSPI flash)",
        core: Core::M0,
        clock_hz: 133_000_000,
        flash_bytes: 2048 * K,
        ram_bytes: 264 * K,
    },
    Chip {
        name: "stm32f411",
        part: "STM32F411CE (\"Black Pill\")",
        core: Core::M4F,
        clock_hz: 100_000_000,
        flash_bytes: 512 * K,
        ram_bytes: 128 * K,
    },
    Chip {
        name: "stm32f103",
        part: "STM32F103C8 (\"Blue Pill\")",
        core: Core::M3,
        clock_hz: 72_000_000,
        flash_bytes: 64 * K,
        ram_bytes: 20 * K,
    },
    Chip {
        name: "nrf52840",
        part: "nRF52840 (Cortex-M4F)",
        core: Core::M4F,
        clock_hz: 64_000_000,
        flash_bytes: 1024 * K,
        ram_bytes: 256 * K,
    },
    Chip {
        name: "esp32c3",
        part: "ESP32-C3 (RV32IMC, 4 MB flash)",
        core: Core::Rv32,
        clock_hz: 160_000_000,
        flash_bytes: 4096 * K,
        ram_bytes: 400 * K,
    },
];

/// The chip named `name`.
pub fn chip(name: &str) -> Option<&'static Chip> {
    CHIPS.iter().find(|c| c.name == name)
}

/// The chips' names, for messages.
pub fn chip_names() -> String {
    CHIPS.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_cores_round_trip() {
        for (i, c) in CHIPS.iter().enumerate() {
            assert_eq!(chip(c.name), Some(c));
            assert!(CHIPS[..i].iter().all(|o| o.name != c.name));
        }
        for c in Core::ALL {
            assert_eq!(Core::from_name(c.name()), Some(c));
        }
        assert_eq!(chip("esp32"), None);
    }
}
