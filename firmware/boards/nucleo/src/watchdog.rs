//! The independent watchdog (IWDG), by register: started first thing at boot, before the
//! clocks, the settings load and the UART set-up, any of which could hang; from then on fed
//! by the stall judge (`plasma_tasks::progress::judge`) only while every task reports progress.

use embassy_stm32::pac;
use embassy_stm32::pac::iwdg::vals::{Key, Pr};
use embassy_time::Timer;

/// IWDG clock: the LSI, 32 kHz nominal (RM0351; 29.5 to 34 kHz over temperature and parts).
const LSI_HZ: u32 = 32_000;
/// LSI / 8: 4 kHz counter.
const PRESCALER: Pr = Pr::DIVIDE_BY8;
const PRESCALER_DIVIDER: u32 = 8;
/// How long the IWDG runs without a feed before it resets the MCU.
const TIMEOUT_MS: u32 = 1_000;
/// Counter reload for [`TIMEOUT_MS`]: 4000 of the 12-bit counter's 4095.
const RELOAD: u16 = {
    let reload = TIMEOUT_MS * (LSI_HZ / PRESCALER_DIVIDER) / 1000;
    assert!(reload <= 0x0FFF, "the IWDG reload is 12 bits");
    reload as u16
};

/// Starts the IWDG (it starts the LSI itself) with a 1 s time-out. Call before anything that
/// could hang: no task feeds it yet, so a boot that stalls for a second resets.
pub fn start() -> Iwdg {
    // Halting the core in a debugger must not reset it.
    pac::DBGMCU.apb1fzr1().modify(|w| w.set_iwdg(true));
    let iwdg = pac::IWDG;
    iwdg.kr().write(|w| w.set_key(Key::START));
    iwdg.kr().write(|w| w.set_key(Key::ENABLE));
    iwdg.pr().write(|w| w.set_pr(PRESCALER));
    iwdg.rlr().write(|w| w.set_rl(RELOAD));
    // The new values reach the LSI domain a few LSI cycles later (PVU, RVU); until then the
    // reset value (LSI / 4, 4095: 512 ms) applies, which is also safe.
    while iwdg.sr().read().0 != 0 {}
    feed();
    Iwdg(())
}

fn feed() {
    pac::IWDG.kr().write(|w| w.set_key(Key::RESET));
}

/// The running IWDG, for the stall judge: only [`start`] makes one.
pub struct Iwdg(());

impl plasma_tasks::board::Watchdog for Iwdg {
    fn feed(&mut self) {
        feed();
    }

    /// No more feeds: the IWDG resets the MCU within [`TIMEOUT_MS`].
    async fn expire(self) {
        loop {
            Timer::after_secs(1).await;
        }
    }
}
