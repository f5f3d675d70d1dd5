//! What the example needs from a RISC-V core (QEMU `virt`, riscv-rt): a tick counter (the
//! CLINT's `mtime`), a loop of known length for the calibration, the stack pointer, exit
//! through the SiFive test device (QEMU's exit code), and the exception report. The other
//! core: `cortex_m.rs`, same items.

use core::ptr::{read_volatile, write_volatile};

pub use riscv_rt::entry;

use crate::board::Uart;
use crate::text::Text;

/// The CLINT's `mtime`, low word: a free-running 32-bit up-counter at 10 MHz on `virt`
/// (`board::SYSTICK_HZ`), driven by QEMU's virtual clock.
///
/// Under `qemu -icount shift=0` every instruction advances virtual time by 1 ns, so ticks are
/// exactly proportional to instructions (ticks per instruction = 10 MHz / 1 GHz), as SysTick's
/// are on the Cortex-M boards; `calibrate` (main.rs) measures the ratio with [`spin`].
pub mod ticks {
    use super::read_volatile;

    const MTIME: usize = 0x0200_BFF8;

    /// Nothing to start: `mtime` always runs.
    pub fn start() -> bool {
        true
    }

    #[inline(always)]
    pub fn now() -> u32 {
        // SAFETY: the CLINT's mtime register of the virt machine (low word).
        unsafe { read_volatile(MTIME as *const u32) }
    }

    /// Ticks from `earlier` to `later` (one wrap at most).
    #[inline(always)]
    pub fn since(earlier: u32, later: u32) -> u32 {
        later.wrapping_sub(earlier)
    }
}

/// Exactly two instructions per iteration: `addi`, `bnez`.
#[inline(never)]
pub fn spin(iterations: u32) {
    // SAFETY: register-only loop; touches no memory and no stack.
    unsafe {
        core::arch::asm!(
            "2:",
            "addi {0}, {0}, -1",
            "bnez {0}, 2b",
            inout(reg) iterations => _,
            options(nomem, nostack),
        );
    }
}

/// The stack pointer.
#[inline(always)]
pub fn stack_pointer() -> usize {
    let sp: usize;
    // SAFETY: reads the stack pointer.
    unsafe { core::arch::asm!("mv {}, sp", out(reg) sp, options(nomem, nostack)) };
    sp
}

/// The SiFive test device of `virt`: 0x5555 ends QEMU with exit code 0, `code << 16 | 0x3333`
/// with exit code `code`.
const TEST_DEVICE: usize = 0x0010_0000;

/// Ends the run: QEMU exits with 0 on success, 1 on failure.
pub fn exit(success: bool) -> ! {
    let value: u32 = if success { 0x5555 } else { 1 << 16 | 0x3333 };
    // SAFETY: the virt machine's test device; the write ends the emulation.
    unsafe { write_volatile(TEST_DEVICE as *mut u32, value) };
    // Reached only outside QEMU.
    loop {
        riscv::asm::wfi();
    }
}

#[export_name = "ExceptionHandler"]
fn exception_handler(frame: &riscv_rt::TrapFrame) -> ! {
    let mut text = Text(Uart::steal());
    text.str("\n# error exception")
        .kv("cause", riscv::register::mcause::read().bits() as u64)
        .kv("pc", riscv::register::mepc::read() as u64)
        .kv("ra", frame.ra as u64)
        .str("\n# end\n");
    exit(false)
}
