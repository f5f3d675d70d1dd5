//! What the example needs from a Cortex-M core: a tick counter (SysTick), a loop of known
//! length for the calibration, the stack pointer, exit through semihosting (QEMU's exit
//! code), and the HardFault report. The other core: `riscv.rs`, same items.

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};

pub use cortex_m_rt::entry;

use crate::board::Uart;
use crate::text::Text;

/// SysTick as a free-running 24-bit down-counter clocked by the core.
///
/// Under `qemu -icount shift=0` every instruction advances virtual time by 1 ns, so ticks are
/// exactly proportional to instructions (ticks per instruction = core clock / 1 GHz).
/// `calibrate` (main.rs) measures that ratio with [`spin`].
pub mod ticks {
    use super::{SystClkSource, SYST};

    const MASK: u32 = 0x00FF_FFFF;

    /// Starts the counter; false if the core peripherals were already taken.
    pub fn start() -> bool {
        let Some(mut core) = cortex_m::Peripherals::take() else {
            return false;
        };
        let syst = &mut core.SYST;
        syst.disable_interrupt();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(MASK);
        syst.clear_current();
        syst.enable_counter();
        true
    }

    #[inline(always)]
    pub fn now() -> u32 {
        SYST::get_current()
    }

    /// Ticks from `earlier` to `later` (one wrap at most: callers keep spans under 2^24 ticks).
    #[inline(always)]
    pub fn since(earlier: u32, later: u32) -> u32 {
        earlier.wrapping_sub(later) & MASK
    }
}

/// Exactly two instructions per iteration: `subs`, `bne`.
#[inline(never)]
pub fn spin(iterations: u32) {
    // SAFETY: register-only loop; touches no memory and no stack.
    unsafe {
        core::arch::asm!(
            "2:",
            "subs r0, #1",
            "bne 2b",
            inout("r0") iterations => _,
            options(nomem, nostack),
        );
    }
}

/// The stack pointer.
#[inline(always)]
pub fn stack_pointer() -> usize {
    let sp: usize;
    // SAFETY: reads the stack pointer.
    unsafe { core::arch::asm!("mov {}, sp", out(reg) sp, options(nomem, nostack)) };
    sp
}

/// Ends the run: QEMU exits with 0 on success, 1 on failure.
pub fn exit(success: bool) -> ! {
    debug::exit(if success { EXIT_SUCCESS } else { EXIT_FAILURE });
    // Reached only when no debugger/emulator handles the semihosting call.
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    let mut text = Text(Uart::steal());
    text.str("\n# error hardfault")
        .kv("pc", u64::from(frame.pc()))
        .str("\n# end\n");
    exit(false)
}
