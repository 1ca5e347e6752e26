//! A debugger's memory write through QEMU's debugger stub (`-gdb tcp:HOST:PORT`), in the GDB
//! remote serial protocol: how a test presses an input the emulated board has no pin for (the
//! QEMU board's e-stop, `ESTOP_INPUT` in the firmware), as a probe writes a target's memory.
//!
//! Written here rather than driving `gdb-multiarch`: two packets (`M`, then `D`) need no
//! debugger installed, and the stub's connection halts the guest only while they are exchanged.

use anyhow::{bail, Context, Result};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// How long the stub may take to answer a packet.
const ANSWER: Duration = Duration::from_secs(10);

/// Writes the little-endian word `value` at `address` of the guest behind the stub at `addr`
/// (`HOST:PORT`) and lets the guest run on. The stub halts the guest when a debugger connects;
/// the detach (`D`) resumes it.
pub fn write_word(addr: &str, address: u32, value: u32) -> Result<()> {
    let mut stub =
        TcpStream::connect(addr).with_context(|| format!("connecting to the gdbstub at {addr}"))?;
    stub.set_read_timeout(Some(ANSWER))?;
    stub.set_nodelay(true)?;
    let data: String = value
        .to_le_bytes()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let wrote = exchange(&mut stub, &format!("M{address:x},4:{data}"))?;
    if wrote != "OK" {
        bail!("the gdbstub refused to write {address:#010x}: {wrote}");
    }
    let detached = exchange(&mut stub, "D")?;
    if detached != "OK" {
        bail!("the gdbstub refused to detach: {detached}");
    }
    Ok(())
}

/// `$body#checksum`, the checksum the modulo-256 sum of the body's bytes.
fn packet(body: &str) -> String {
    let sum = body.bytes().fold(0u8, |a, b| a.wrapping_add(b));
    format!("${body}#{sum:02x}")
}

/// Sends `body` (again on a `-`, at most three times) and returns the stub's answer, acknowledged.
/// The stop notice the stub sends when its connection halts the guest (`T..` or `S..`) may come
/// before the ack or the answer: it is acknowledged and passed over.
fn exchange(stub: &mut TcpStream, body: &str) -> Result<String> {
    for _ in 0..3 {
        stub.write_all(packet(body).as_bytes())?;
        if !acknowledged(stub)? {
            continue;
        }
        loop {
            let answer = read_packet(stub)?;
            stub.write_all(b"+")?;
            if !is_stop_notice(&answer) {
                return Ok(answer);
            }
        }
    }
    bail!("the gdbstub rejected `{body}` three times")
}

/// Whether the stub took the packet just sent (`+`) or asks for it again (`-`).
fn acknowledged(stub: &mut TcpStream) -> Result<bool> {
    loop {
        match read_byte(stub)? {
            b'+' => return Ok(true),
            b'-' => return Ok(false),
            b'$' => {
                let notice = read_body(stub)?;
                stub.write_all(b"+")?;
                if !is_stop_notice(&notice) {
                    bail!("the gdbstub answered `{notice}` before taking the packet");
                }
            }
            other => bail!(
                "the gdbstub answered {:?} where an ack was due",
                other as char
            ),
        }
    }
}

/// A stop reply: the guest halted (`S` signal, or `T` signal and registers).
fn is_stop_notice(answer: &str) -> bool {
    answer.starts_with('T') || answer.starts_with('S')
}

/// One `$...#xx` packet's body (its checksum checked).
fn read_packet(stub: &mut TcpStream) -> Result<String> {
    while read_byte(stub)? != b'$' {}
    read_body(stub)
}

/// The rest of a packet after its `$`: the body, its checksum checked.
fn read_body(stub: &mut TcpStream) -> Result<String> {
    let mut body = Vec::new();
    loop {
        match read_byte(stub)? {
            b'#' => break,
            b => body.push(b),
        }
    }
    let sum = [read_byte(stub)?, read_byte(stub)?];
    let sum = u8::from_str_radix(std::str::from_utf8(&sum)?, 16)?;
    if body.iter().fold(0u8, |a, b| a.wrapping_add(*b)) != sum {
        bail!("a packet from the gdbstub failed its checksum");
    }
    Ok(String::from_utf8_lossy(&body).into_owned())
}

fn read_byte(stub: &mut TcpStream) -> Result<u8> {
    let mut b = [0u8];
    stub.read_exact(&mut b)
        .context("the gdbstub closed or did not answer")?;
    Ok(b[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::TcpListener;

    #[test]
    fn packets_carry_the_protocols_checksum() {
        // From the protocol's documentation: `$g#67` reads the registers.
        assert_eq!(packet("g"), "$g#67");
        assert_eq!(packet("OK"), "$OK#9a");
        assert_eq!(packet("D"), "$D#44");
    }

    /// A stand-in stub: acks each packet, answers OK, and records what it was sent; QEMU's
    /// stop notice on connecting if `notice_first`.
    fn stub(nack_first: bool, notice_first: bool) -> (String, std::thread::JoinHandle<Vec<u8>>) {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap().to_string();
        let h = std::thread::spawn(move || {
            let (mut s, _) = l.accept().unwrap();
            if notice_first {
                // Its ack comes after the client's first packet, which reading a packet skips.
                s.write_all(packet("T02thread:01;").as_bytes()).unwrap();
            }
            let mut seen = Vec::new();
            let mut nack = nack_first;
            for _ in 0..2 + usize::from(nack_first) {
                let p = read_packet(&mut s).unwrap();
                seen.extend_from_slice(p.as_bytes());
                seen.push(b'|');
                if std::mem::take(&mut nack) {
                    s.write_all(b"-").unwrap();
                    continue;
                }
                s.write_all(b"+").unwrap();
                s.write_all(packet("OK").as_bytes()).unwrap();
                assert_eq!(read_byte(&mut s).unwrap(), b'+');
            }
            seen
        });
        (addr, h)
    }

    #[test]
    fn a_word_is_written_little_endian_then_the_guest_released() {
        let (addr, h) = stub(false, false);
        write_word(&addr, 0x2000_0010, 1).unwrap();
        assert_eq!(h.join().unwrap(), b"M20000010,4:01000000|D|");
    }

    #[test]
    fn a_rejected_packet_is_sent_again() {
        let (addr, h) = stub(true, false);
        write_word(&addr, 0x2000_0010, 0x0102_0304).unwrap();
        assert_eq!(
            h.join().unwrap(),
            b"M20000010,4:04030201|M20000010,4:04030201|D|"
        );
    }

    #[test]
    fn the_stop_notice_on_connecting_is_passed_over() {
        let (addr, h) = stub(false, true);
        write_word(&addr, 0x2000_0010, 1).unwrap();
        assert_eq!(h.join().unwrap(), b"M20000010,4:01000000|D|");
    }

    #[test]
    fn no_stub_is_an_error_naming_the_address() {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap().to_string();
        drop(l);
        let e = write_word(&addr, 0, 0).unwrap_err();
        assert!(format!("{e:#}").contains(&addr), "{e:#}");
    }
}
