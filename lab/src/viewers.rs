//! Where 3D Slicer listens or connects: `needle steer --slicer HOST:PORT` connects to Slicer's
//! OpenIGTLinkIF server; `--serve-slicer PORT` is the server Slicer's connector (type Client)
//! connects to, as it connects to PLUS. A viewer that joins late is first sent the scene (the
//! plan, the obstacles, the state so far); one that fails or leaves is dropped and steering goes
//! on. Frames are encoded once and written to every viewer.

use anyhow::{anyhow, Context, Result};
use std::io::Write;
use std::net::{IpAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// A write to a viewer may block this long before the viewer is dropped: a stalled Slicer must
/// not stall the insertion.
const WRITE_TIMEOUT: Duration = Duration::from_millis(200);

/// The viewers of the insertion.
#[derive(Default)]
pub enum Viewers {
    /// Nobody is shown anything.
    #[default]
    None,
    /// One Slicer this program connected to; `None` once it failed.
    Connected(Option<TcpStream>),
    /// Slicers that connected to this program's server.
    Served {
        /// The server (non-blocking).
        listener: TcpListener,
        /// The viewers connected now.
        viewers: Vec<TcpStream>,
        /// The frames a viewer that joins is sent first.
        scene: Vec<Vec<u8>>,
    },
}

impl Viewers {
    /// Connects to Slicer's server at `address`.
    pub fn connect(address: &str) -> Result<Viewers> {
        let addr = address
            .to_socket_addrs()
            .with_context(|| format!("Slicer address {address}"))?
            .next()
            .ok_or_else(|| anyhow!("Slicer address {address} resolves to nothing"))?;
        let conn = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
            .with_context(|| format!("cannot reach Slicer at {address}"))?;
        conn.set_nodelay(true)?;
        conn.set_write_timeout(Some(WRITE_TIMEOUT))?;
        Ok(Viewers::Connected(Some(conn)))
    }

    /// Serves Slicer on `at` (an address and a port; port 0 picks a free one) and, for up to
    /// `wait`, waits for the first viewer to connect. Only hosts that reach the address can
    /// connect: 127.0.0.1 is this machine alone.
    pub fn serve(at: (IpAddr, u16), wait: Duration) -> Result<Viewers> {
        let (ip, port) = at;
        let listener = TcpListener::bind(at)
            .with_context(|| format!("cannot serve Slicer on {ip} port {port}"))?;
        let bound = listener.local_addr()?;
        eprintln!(
            "needle steer: serving Slicer on port {} of {}",
            bound.port(),
            bound.ip()
        );
        listener.set_nonblocking(true)?;
        let mut viewers = Viewers::Served {
            listener,
            viewers: Vec::new(),
            scene: Vec::new(),
        };
        let until = Instant::now() + wait;
        while viewers.count() == 0 && Instant::now() < until {
            viewers.accept();
            std::thread::sleep(Duration::from_millis(20));
        }
        Ok(viewers)
    }

    /// Whether anything sent may reach a viewer, now or (served) later.
    pub fn active(&self) -> bool {
        match self {
            Viewers::None => false,
            Viewers::Connected(conn) => conn.is_some(),
            Viewers::Served { .. } => true,
        }
    }

    /// The port served on, if serving.
    pub fn port(&self) -> Option<u16> {
        self.served_on().map(|a| a.port())
    }

    /// The address served on, if serving.
    pub fn served_on(&self) -> Option<std::net::SocketAddr> {
        match self {
            Viewers::Served { listener, .. } => listener.local_addr().ok(),
            _ => None,
        }
    }

    /// Viewers connected now.
    pub fn count(&self) -> usize {
        match self {
            Viewers::None => 0,
            Viewers::Connected(conn) => usize::from(conn.is_some()),
            Viewers::Served { viewers, .. } => viewers.len(),
        }
    }

    /// Takes the viewers that connected since, each sent the scene first.
    fn accept(&mut self) {
        let Viewers::Served {
            listener,
            viewers,
            scene,
        } = self
        else {
            return;
        };
        while let Ok((mut conn, _)) = listener.accept() {
            let ready = conn.set_nonblocking(false).is_ok()
                && conn.set_nodelay(true).is_ok()
                && conn.set_write_timeout(Some(WRITE_TIMEOUT)).is_ok();
            if ready && scene.iter().all(|f| conn.write_all(f).is_ok()) {
                viewers.push(conn);
            }
        }
    }

    /// Writes one encoded frame to every viewer; `scene` frames are also kept for viewers that
    /// join later. A connected Slicer that fails is reported (`Err`) and dropped; a served
    /// viewer that fails is dropped quietly (it may join again).
    pub fn deliver(&mut self, frame: &[u8], scene: bool) -> std::io::Result<()> {
        self.accept();
        match self {
            Viewers::None => Ok(()),
            Viewers::Connected(conn) => {
                let Some(c) = conn.as_mut() else {
                    return Ok(());
                };
                let sent = c.write_all(frame).and_then(|()| c.flush());
                if sent.is_err() {
                    *conn = None;
                }
                sent
            }
            Viewers::Served {
                viewers,
                scene: kept,
                ..
            } => {
                viewers.retain_mut(|v| v.write_all(frame).and_then(|()| v.flush()).is_ok());
                if scene {
                    kept.push(frame.to_vec());
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn read_exactly(conn: &mut TcpStream, n: usize) -> Vec<u8> {
        let mut buf = vec![0u8; n];
        conn.read_exact(&mut buf).unwrap();
        buf
    }

    #[test]
    fn a_viewer_that_joins_late_gets_the_scene_then_what_follows() {
        let loopback = IpAddr::from([127, 0, 0, 1]);
        let mut viewers = Viewers::serve((loopback, 0), Duration::ZERO).unwrap();
        let port = viewers.port().unwrap();
        viewers.deliver(b"plan;", true).unwrap();
        viewers.deliver(b"tip-1;", false).unwrap();
        assert_eq!(viewers.count(), 0);
        let mut late = TcpStream::connect(("127.0.0.1", port)).unwrap();
        late.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        // The next frame accepts it: the scene first, not what it missed, then the frame.
        viewers.deliver(b"tip-2;", false).unwrap();
        assert_eq!(viewers.count(), 1);
        assert_eq!(read_exactly(&mut late, 11), b"plan;tip-2;");
        // A viewer that leaves is dropped; steering's frames still go out without error.
        drop(late);
        for _ in 0..50 {
            viewers.deliver(&[0u8; 4096], false).unwrap();
            if viewers.count() == 0 {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        assert_eq!(viewers.count(), 0);
    }
}
