//! `needle steer --serve-slicer` serves this machine only unless told otherwise: OpenIGTLink has
//! no authentication, so anyone who can connect sees the plan and the insertion. By default a
//! connection on another local address (127.0.0.2, which the loopback interface also carries,
//! and the machine's own network address when it has one) is refused while one on 127.0.0.1 is
//! served; `--serve-slicer-bind 0.0.0.0` widens it to every interface.

mod lab_support;

use lab_support::Lab;
use needle_e2e::example;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// The machine's address on its network, if it has one (the source address of a route out;
/// no packet is sent).
fn network_address() -> Option<IpAddr> {
    let probe = UdpSocket::bind("0.0.0.0:0").ok()?;
    probe.connect("192.0.2.1:9").ok()?;
    let ip = probe.local_addr().ok()?.ip();
    (!ip.is_loopback() && !ip.is_unspecified()).then_some(ip)
}

/// Other local addresses than 127.0.0.1 to try.
fn other_addresses() -> Vec<IpAddr> {
    let mut v = vec![IpAddr::V4(Ipv4Addr::new(127, 0, 0, 2))];
    v.extend(network_address());
    v
}

fn connect(ip: IpAddr, port: u16) -> std::io::Result<TcpStream> {
    TcpStream::connect_timeout(&SocketAddr::new(ip, port), Duration::from_secs(2))
}

/// Steers with `--serve-slicer` (and `extra`), and once a viewer got in on 127.0.0.1, tries each
/// other local address while `needle steer` still serves: whether each connected.
fn reachable_while_serving(extra: &[&str]) -> Vec<(IpAddr, bool)> {
    let file = example("paper").to_str().unwrap().to_string();
    // 40 pieces a second: the insertion lasts over 3 s, serving all along.
    let lab = Lab::start(&file, 1, &["--rate", "40"]);
    let port = TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port();
    let port_text = port.to_string();
    let mut args = vec!["--serve-slicer", &port_text, "--wait-for-slicer", "30"];
    args.extend_from_slice(extra);
    let mut child = lab
        .steer_command(&file, &args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start needle steer");
    let started = Instant::now();
    let _viewer = loop {
        if let Ok(c) = connect(IpAddr::V4(Ipv4Addr::LOCALHOST), port) {
            break c;
        }
        assert!(started.elapsed() < Duration::from_secs(30), "never served");
        std::thread::sleep(Duration::from_millis(20));
    };
    let tried: Vec<(IpAddr, bool)> = other_addresses()
        .into_iter()
        .map(|ip| (ip, connect(ip, port).is_ok()))
        .collect();
    assert!(
        child.try_wait().unwrap().is_none(),
        "still serving when the others were tried"
    );
    let _ = child.wait();
    tried
}

#[test]
fn the_viewer_port_is_on_loopback_by_default() {
    let tried = reachable_while_serving(&[]);
    assert!(tried.iter().all(|(_, ok)| !ok), "{tried:?}");
    println!("refused on {tried:?}");
}

#[test]
fn serve_slicer_bind_widens_it() {
    let tried = reachable_while_serving(&["--serve-slicer-bind", "0.0.0.0"]);
    assert!(tried.iter().all(|(_, ok)| *ok), "{tried:?}");
}
