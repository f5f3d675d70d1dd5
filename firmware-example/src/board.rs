//! What the example needs from each board: its UART at 115200 8N1 — transmit for the text
//! output, receive (non-blocking, [`Rx::read_byte`]) for the streaming mode — and how much
//! RAM the streaming mode may give a received clip ([`CLIP_BUFFER_BYTES`]).
//!
//! Raw register access on purpose: no PAC/HAL per board, so the three boards share one
//! dependency set and the flash figures show the decoder, not a HAL. QEMU ignores the baud
//! rate; the values are the real boards' so the same binary also talks on hardware. QEMU
//! feeds the receiver from the `-serial` chardev only while the UART has room (PL011: its
//! 16-byte FIFO; nRF51: 6 bytes; CMSDK: one byte), so input from a file is never lost.

use core::ptr::{read_volatile, write_volatile};

#[cfg_attr(feature = "board-riscv-virt", allow(dead_code))] // byte-wide registers there
#[inline(always)]
fn write_reg(addr: usize, value: u32) {
    // SAFETY: callers pass addresses of this board's memory-mapped UART/clock registers.
    unsafe { write_volatile(addr as *mut u32, value) }
}

#[cfg_attr(feature = "board-riscv-virt", allow(dead_code))]
#[inline(always)]
fn read_reg(addr: usize) -> u32 {
    // SAFETY: as for `write_reg`.
    unsafe { read_volatile(addr as *const u32) }
}

/// Byte sink behind the text output.
pub trait Write {
    /// Blocks until the byte is handed to the UART.
    fn write_byte(&mut self, byte: u8);
}

/// The receive side of the board's UART (set up by `Uart::init`).
pub struct Rx(());

impl Rx {
    /// The receiver; call after `Uart::init`.
    pub fn take() -> Self {
        Rx(())
    }

    /// The next received byte, if one is waiting.
    pub fn read_byte(&mut self) -> Option<u8> {
        imp::read_byte()
    }
}

#[cfg(feature = "board-lm3s6965")]
mod imp {
    //! TI Stellaris LM3S6965 UART0 (an ARM PL011) on PA0/PA1.
    use super::{read_reg, write_reg};

    pub const NAME: &str = "lm3s6965";

    const SYSCTL_RCGC1: usize = 0x400F_E104; // bit 0: UART0 clock
    const SYSCTL_RCGC2: usize = 0x400F_E108; // bit 0: GPIO port A clock
    const GPIOA_AFSEL: usize = 0x4000_4420;
    const GPIOA_DEN: usize = 0x4000_451C;
    const UART0: usize = 0x4000_C000;
    const DR: usize = UART0; // data
    const FR: usize = UART0 + 0x18; // flags
    const IBRD: usize = UART0 + 0x24;
    const FBRD: usize = UART0 + 0x28;
    const LCRH: usize = UART0 + 0x2C;
    const CR: usize = UART0 + 0x30;
    const FR_TXFF: u32 = 1 << 5; // transmit FIFO full
    const FR_RXFE: u32 = 1 << 4; // receive FIFO empty

    /// 64 KB of RAM: 32 KB for a streamed clip.
    pub const CLIP_BUFFER_BYTES: usize = 32 * 1024;
    /// SysTick (core clock source) ticks per second: QEMU's lm3s6965evb core clock.
    pub const SYSTICK_HZ: u32 = 12_500_000;

    pub fn read_byte() -> Option<u8> {
        if read_reg(FR) & FR_RXFE != 0 {
            return None;
        }
        // Bits 8–11 are the byte's framing/parity/break/overrun flags: a damaged byte is
        // still passed on, and the frame's CRC rejects it.
        Some(read_reg(DR) as u8)
    }

    pub struct Uart(());

    impl Uart {
        pub fn init() -> Self {
            // Only UART0 (reset state has every other clock off; setting more wakes QEMU timers).
            write_reg(SYSCTL_RCGC1, 1);
            write_reg(SYSCTL_RCGC2, read_reg(SYSCTL_RCGC2) | 1);
            write_reg(GPIOA_AFSEL, read_reg(GPIOA_AFSEL) | 0b11);
            write_reg(GPIOA_DEN, read_reg(GPIOA_DEN) | 0b11);
            write_reg(CR, 0); // disabled while configuring
                              // 12 MHz reset clock / (16 * 115200) = 6.51: integer 6, fraction 0.51 * 64 = 33.
            write_reg(IBRD, 6);
            write_reg(FBRD, 33);
            write_reg(LCRH, 0b11 << 5 | 1 << 4); // 8 bits, FIFOs on
            write_reg(CR, 1 << 9 | 1 << 8 | 1); // RXE, TXE, UARTEN
            Uart(())
        }

        /// The UART as configured by an earlier `init` (panic and fault handlers).
        pub fn steal() -> Self {
            Uart(())
        }
    }

    impl super::Write for Uart {
        fn write_byte(&mut self, byte: u8) {
            while read_reg(FR) & FR_TXFF != 0 {}
            write_reg(DR, u32::from(byte));
        }
    }
}

#[cfg(feature = "board-microbit")]
mod imp {
    //! Nordic nRF51822 UART0, TX on P0.24 (the micro:bit's USB serial).
    use super::{read_reg, write_reg};

    pub const NAME: &str = "microbit";

    /// 16 KB of RAM: 6 KB for a streamed clip (the rest is the stack, about 6 KB).
    pub const CLIP_BUFFER_BYTES: usize = 6 * 1024;
    /// SysTick (core clock source) ticks per second: the nRF51's 16 MHz core clock.
    pub const SYSTICK_HZ: u32 = 16_000_000;

    pub fn read_byte() -> Option<u8> {
        if read_reg(EVENTS_RXDRDY) == 0 {
            return None;
        }
        // Clear the event before reading RXD: reading it moves the next byte in and raises
        // the event again.
        write_reg(EVENTS_RXDRDY, 0);
        Some(read_reg(RXD) as u8)
    }

    const UART0: usize = 0x4000_2000;
    const TASKS_STARTRX: usize = UART0; // offset 0x000
    const TASKS_STARTTX: usize = UART0 + 0x008;
    const EVENTS_RXDRDY: usize = UART0 + 0x108;
    const EVENTS_TXDRDY: usize = UART0 + 0x11C;
    const RXD: usize = UART0 + 0x518;
    const ENABLE: usize = UART0 + 0x500;
    const PSELTXD: usize = UART0 + 0x50C;
    const PSELRXD: usize = UART0 + 0x514;
    const TXD: usize = UART0 + 0x51C;
    const BAUDRATE: usize = UART0 + 0x524;

    pub struct Uart(());

    impl Uart {
        pub fn init() -> Self {
            write_reg(PSELTXD, 24);
            write_reg(PSELRXD, 25);
            write_reg(BAUDRATE, 0x01D7_E000); // 115200
            write_reg(ENABLE, 4);
            write_reg(TASKS_STARTTX, 1);
            write_reg(TASKS_STARTRX, 1);
            Uart(())
        }

        /// The UART as configured by an earlier `init` (panic and fault handlers).
        pub fn steal() -> Self {
            Uart(())
        }
    }

    impl super::Write for Uart {
        fn write_byte(&mut self, byte: u8) {
            write_reg(EVENTS_TXDRDY, 0);
            write_reg(TXD, u32::from(byte));
            while read_reg(EVENTS_TXDRDY) == 0 {}
        }
    }
}

#[cfg(feature = "board-mps2-an386")]
mod imp {
    //! Arm CMSDK APB UART0 of the MPS2 AN386 image.
    use super::{read_reg, write_reg};

    pub const NAME: &str = "mps2-an386";

    const UART0: usize = 0x4000_4000;
    const DATA: usize = UART0;
    const STATE: usize = UART0 + 0x4;
    const CTRL: usize = UART0 + 0x8;
    const BAUDDIV: usize = UART0 + 0x10;
    const STATE_TX_FULL: u32 = 1;
    const STATE_RX_FULL: u32 = 1 << 1;
    const CTRL_TX_EN: u32 = 1;
    const CTRL_RX_EN: u32 = 1 << 1;

    /// 4 MB of RAM: 64 KB for a streamed clip.
    pub const CLIP_BUFFER_BYTES: usize = 64 * 1024;
    /// SysTick (core clock source) ticks per second: the MPS2's 25 MHz core clock.
    pub const SYSTICK_HZ: u32 = 25_000_000;

    pub fn read_byte() -> Option<u8> {
        if read_reg(STATE) & STATE_RX_FULL == 0 {
            return None;
        }
        Some(read_reg(DATA) as u8)
    }

    pub struct Uart(());

    impl Uart {
        pub fn init() -> Self {
            write_reg(BAUDDIV, 25_000_000 / 115_200); // 25 MHz peripheral clock
            write_reg(CTRL, CTRL_TX_EN | CTRL_RX_EN);
            Uart(())
        }

        /// The UART as configured by an earlier `init` (panic and fault handlers).
        pub fn steal() -> Self {
            Uart(())
        }
    }

    impl super::Write for Uart {
        fn write_byte(&mut self, byte: u8) {
            while read_reg(STATE) & STATE_TX_FULL != 0 {}
            write_reg(DATA, u32::from(byte));
        }
    }
}

#[cfg(not(any(
    feature = "board-lm3s6965",
    feature = "board-microbit",
    feature = "board-mps2-an386",
    feature = "board-riscv-virt"
)))]
compile_error!(
    "enable one board feature: board-lm3s6965, board-microbit, board-mps2-an386 or board-riscv-virt"
);

#[cfg(feature = "board-riscv-virt")]
mod imp {
    //! QEMU `virt` (riscv32): UART0 is an NS16550A at 0x1000_0000 with byte-wide registers.
    use core::ptr::{read_volatile, write_volatile};

    pub const NAME: &str = "riscv-virt";

    const UART0: usize = 0x1000_0000;
    const RBR_THR: usize = UART0; // receive buffer / transmit holding (DLAB = 0)
    const IER: usize = UART0 + 1;
    const FCR: usize = UART0 + 2;
    const LCR: usize = UART0 + 3;
    const LSR: usize = UART0 + 5;
    const LSR_DATA_READY: u8 = 1;
    const LSR_THR_EMPTY: u8 = 1 << 5;

    pub const CLIP_BUFFER_BYTES: usize = 32 * 1024;
    /// The tick counter is the CLINT's `mtime` (src/arch/riscv.rs), 10 MHz on `virt`.
    pub const SYSTICK_HZ: u32 = 10_000_000;

    #[inline(always)]
    fn write8(addr: usize, value: u8) {
        // SAFETY: addresses of the virt machine's UART registers.
        unsafe { write_volatile(addr as *mut u8, value) }
    }

    #[inline(always)]
    fn read8(addr: usize) -> u8 {
        // SAFETY: as for `write8`.
        unsafe { read_volatile(addr as *const u8) }
    }

    pub fn read_byte() -> Option<u8> {
        if read8(LSR) & LSR_DATA_READY == 0 {
            return None;
        }
        Some(read8(RBR_THR))
    }

    pub struct Uart(());

    impl Uart {
        pub fn init() -> Self {
            write8(IER, 0); // polled
            write8(LCR, 0b11); // 8N1, DLAB = 0 (QEMU ignores the divisor)
            write8(FCR, 1); // FIFOs on
            Uart(())
        }

        pub fn steal() -> Self {
            Uart(())
        }
    }

    impl super::Write for Uart {
        fn write_byte(&mut self, byte: u8) {
            while read8(LSR) & LSR_THR_EMPTY == 0 {}
            write8(RBR_THR, byte);
        }
    }
}

pub use imp::{Uart, CLIP_BUFFER_BYTES, NAME, SYSTICK_HZ};
