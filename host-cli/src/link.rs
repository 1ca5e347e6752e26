//! How a command reaches a device (`send`, `ping`, `info`, `motion`): the flags of
//! `needle_device::LinkOptions`.

use needle_device::LinkOptions;

/// How to reach the device, shared by `send`, `ping` and `info`.
#[derive(clap::Args, Clone, Debug)]
pub struct LinkArgs {
    /// Serial port of the device (see `needle ports`; hil-sim prints a /dev/pts path).
    #[arg(long, required_unless_present = "tcp", conflicts_with = "tcp")]
    port: Option<String>,
    /// Baud rate of the serial port.
    #[arg(long, default_value_t = LinkOptions::default().baud)]
    baud: u32,
    /// TCP address of the device instead of a serial port (QEMU, `hil-sim --tcp`).
    #[arg(long)]
    tcp: Option<String>,
    /// Seconds of silence allowed per exchange (no frame at all, intact or damaged, from the
    /// device), and the longest silence while it plans.
    #[arg(long, default_value_t = LinkOptions::default().timeout)]
    timeout: f64,
    /// Times one request is repeated (after a damaged frame, at once; after silence, at an
    /// interval adapted to the round trip) before giving up.
    #[arg(long, default_value_t = LinkOptions::default().retries)]
    retries: u32,
    /// Seconds the whole command (greeting, upload, planning, fetch) may take.
    #[arg(long, default_value_t = LinkOptions::default().deadline)]
    deadline: f64,
}

impl LinkArgs {
    /// The link the flags say.
    pub fn options(&self) -> LinkOptions {
        LinkOptions {
            port: self.port.clone(),
            baud: self.baud,
            tcp: self.tcp.clone(),
            timeout: self.timeout,
            retries: self.retries,
            deadline: self.deadline,
        }
    }
}
