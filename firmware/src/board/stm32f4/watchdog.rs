//! The independent watchdog: a wedged firmware resets within about 4 s.
//!
//! The service loop feeds it once per `poll`, and a `poll` plans at most one form, which takes
//! well under a second at 168 MHz; a hang anywhere else ends in a reset.

use super::pac;

/// The 32 kHz LSI divided by 64 gives 500 ticks/s; 2000 ticks is 4 s.
const RELOAD_TICKS: u16 = 2000;

/// A running watchdog.
pub struct Watchdog {
    iwdg: pac::IWDG,
}

/// Starts the watchdog; it cannot be stopped until the next reset.
pub fn start(iwdg: pac::IWDG) -> Watchdog {
    iwdg.kr().write(|w| w.key().unlock());
    iwdg.pr().write(|w| w.pr().divide_by64());
    iwdg.rlr().write(|w| w.rl().set(RELOAD_TICKS));
    iwdg.kr().write(|w| w.key().start());
    let watchdog = Watchdog { iwdg };
    watchdog.feed();
    watchdog
}

impl Watchdog {
    /// Restarts the countdown.
    pub fn feed(&self) {
        self.iwdg.kr().write(|w| w.key().feed());
    }
}
