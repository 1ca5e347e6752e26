//! A QEMU TCG plugin (plugin API v1, QEMU 7.2+) that counts, exactly, the guest instructions the
//! firmware executes inside marked regions.
//!
//! The firmware brackets measured work with 16-bit Thumb marker instructions it never emits
//! otherwise (see `firmware/src/marker.rs`):
//! - `mov r10, r10` (0x46D2) begins a region,
//! - `mov r11, r11` (0x46DB) ends it and adds its count to the running sum,
//! - `mov r12, r12` (0x46E4) reports the sum, the number of regions and the largest region (one
//!   line) and resets them.
//!
//! Every instruction except the markers gets an inline 64-bit add, so a sum counts exactly the
//! instructions executed between markers, whatever the translation-block boundaries, interrupts or
//! `-icount` setting.
//!
//! Usage: `qemu-system-arm ... -plugin libinsn_count.so[,out=FILE][,profile=FILE] -d plugin [-D LOG]`.
//! Each report is a line `insn-count: <sum> instructions in <regions> regions, largest <max>`
//! (the largest single region: a step interrupt's worst case), appended to the
//! `out` FILE when given (and flushed at once, so a reader sees it while QEMU runs), else written
//! to QEMU's plugin log. With `profile=FILE`, the instructions inside regions are also attributed
//! to the translation block that executed them, and written at exit as `<hex address> <count>`
//! lines (map them to functions with the firmware's symbol table; slower).

use qemu_plugin_sys::{
    qemu_info_t, qemu_plugin_cb_flags, qemu_plugin_id_t, qemu_plugin_insn_data,
    qemu_plugin_insn_size, qemu_plugin_op, qemu_plugin_outs, qemu_plugin_register_atexit_cb,
    qemu_plugin_register_vcpu_insn_exec_cb, qemu_plugin_register_vcpu_insn_exec_inline,
    qemu_plugin_register_vcpu_tb_exec_cb, qemu_plugin_register_vcpu_tb_trans_cb, qemu_plugin_tb,
    qemu_plugin_tb_get_insn, qemu_plugin_tb_n_insns, qemu_plugin_tb_vaddr, QEMU_PLUGIN_VERSION,
};
use std::collections::HashMap;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The plugin API version this plugin was written against; QEMU refuses a mismatch.
#[no_mangle]
pub static qemu_plugin_version: c_int = QEMU_PLUGIN_VERSION as c_int;

/// The marker instructions, as little-endian bytes.
const BEGIN: [u8; 2] = 0x46D2u16.to_le_bytes();
const END: [u8; 2] = 0x46DBu16.to_le_bytes();
const REPORT: [u8; 2] = 0x46E4u16.to_le_bytes();

#[derive(Clone, Copy)]
#[repr(usize)]
enum Marker {
    Begin = 1,
    End = 2,
    Report = 3,
}

/// Guest instructions executed so far, markers excluded (TCG adds to it inline).
static EXECUTED: AtomicU64 = AtomicU64::new(0);

/// Instructions by translation-block address.
type Histogram = HashMap<u64, u64>;

struct Regions {
    open_at: Option<u64>,
    sum: u64,
    regions: u64,
    largest: u64,
    reports: u64,
    out: Option<File>,
    /// Profile file, the histogram of counted regions, and that of the region now open (merged
    /// at `end`, dropped at a `begin` that restarts it).
    profile: Option<(File, Histogram, Histogram)>,
}

static STATE: Mutex<Regions> = Mutex::new(Regions {
    open_at: None,
    sum: 0,
    regions: 0,
    largest: 0,
    reports: 0,
    out: None,
    profile: None,
});

fn emit(state: &mut Regions, line: &str) {
    match state.out.as_mut() {
        Some(f) => {
            // The host reads the file while QEMU runs: write whole lines and flush each.
            let _ = f.write_all(line.as_bytes());
            let _ = f.flush();
        }
        None => {
            if let Ok(c) = CString::new(line) {
                // SAFETY: `c` is a valid NUL-terminated string for the duration of the call.
                unsafe { qemu_plugin_outs(c.as_ptr()) };
            }
        }
    }
}

unsafe extern "C" fn on_marker(_vcpu: c_uint, userdata: *mut c_void) {
    let now = EXECUTED.load(Ordering::Relaxed);
    let Ok(mut state) = STATE.lock() else { return };
    match userdata as usize {
        m if m == Marker::Begin as usize => {
            state.open_at = Some(now);
            if let Some((_, _, open)) = state.profile.as_mut() {
                open.clear();
            }
        }
        m if m == Marker::End as usize => {
            if let Some(start) = state.open_at.take() {
                state.sum += now - start;
                state.regions += 1;
                state.largest = state.largest.max(now - start);
                if let Some((_, counted, open)) = state.profile.as_mut() {
                    for (addr, n) in open.drain() {
                        *counted.entry(addr).or_insert(0) += n;
                    }
                }
            }
        }
        m if m == Marker::Report as usize => {
            let line = format!(
                "insn-count: {} instructions in {} regions, largest {}\n",
                state.sum, state.regions, state.largest
            );
            emit(&mut state, &line);
            state.sum = 0;
            state.regions = 0;
            state.largest = 0;
            state.reports += 1;
        }
        _ => {}
    }
}

fn marker_of(bytes: &[u8]) -> Option<Marker> {
    match bytes {
        b if b == BEGIN => Some(Marker::Begin),
        b if b == END => Some(Marker::End),
        b if b == REPORT => Some(Marker::Report),
        _ => None,
    }
}

/// Translation-block execution while profiling: `userdata` packs the block's address (high 32
/// bits) and its non-marker instruction count (low 32 bits).
unsafe extern "C" fn on_block(_vcpu: c_uint, userdata: *mut c_void) {
    let packed = userdata as usize as u64;
    let Ok(mut state) = STATE.lock() else { return };
    if state.open_at.is_none() {
        return;
    }
    if let Some((_, _, open)) = state.profile.as_mut() {
        *open.entry(packed >> 32).or_insert(0) += packed & 0xFFFF_FFFF;
    }
}

unsafe extern "C" fn on_translate(_id: qemu_plugin_id_t, tb: *mut qemu_plugin_tb) {
    // SAFETY (whole function): QEMU passes a TB handle valid for this callback; instruction
    // handles and their bytes are valid for the same duration and are not kept.
    let n = qemu_plugin_tb_n_insns(tb);
    let profiling = STATE.lock().is_ok_and(|s| s.profile.is_some());
    if profiling {
        let plain = (0..n)
            .filter(|&i| {
                let insn = qemu_plugin_tb_get_insn(tb, i);
                let data = qemu_plugin_insn_data(insn) as *const u8;
                let size = qemu_plugin_insn_size(insn);
                data.is_null() || marker_of(std::slice::from_raw_parts(data, size)).is_none()
            })
            .count() as u64;
        let packed = (qemu_plugin_tb_vaddr(tb) << 32) | plain;
        qemu_plugin_register_vcpu_tb_exec_cb(
            tb,
            Some(on_block),
            qemu_plugin_cb_flags::QEMU_PLUGIN_CB_NO_REGS,
            packed as usize as *mut c_void,
        );
    }
    for i in 0..n {
        let insn = qemu_plugin_tb_get_insn(tb, i);
        let size = qemu_plugin_insn_size(insn);
        let data = qemu_plugin_insn_data(insn) as *const u8;
        let bytes = if data.is_null() {
            &[][..]
        } else {
            std::slice::from_raw_parts(data, size)
        };
        match marker_of(bytes) {
            Some(m) => qemu_plugin_register_vcpu_insn_exec_cb(
                insn,
                Some(on_marker),
                qemu_plugin_cb_flags::QEMU_PLUGIN_CB_NO_REGS,
                m as usize as *mut c_void,
            ),
            None => qemu_plugin_register_vcpu_insn_exec_inline(
                insn,
                qemu_plugin_op::QEMU_PLUGIN_INLINE_ADD_U64,
                EXECUTED.as_ptr() as *mut c_void,
                1,
            ),
        }
    }
}

unsafe extern "C" fn on_exit(_id: qemu_plugin_id_t, _userdata: *mut c_void) {
    if let Ok(mut state) = STATE.lock() {
        let line = format!(
            "insn-count: exit after {} reports, {} instructions in total\n",
            state.reports,
            EXECUTED.load(Ordering::Relaxed)
        );
        emit(&mut state, &line);
        if let Some((mut file, hist, _)) = state.profile.take() {
            let mut rows: Vec<_> = hist.into_iter().collect();
            rows.sort_by_key(|r| std::cmp::Reverse(r.1));
            for (addr, count) in rows {
                let _ = writeln!(file, "{addr:#010x} {count}");
            }
        }
    }
}

/// Plugin entry point: parses `out=FILE` and registers the callbacks.
///
/// # Safety
/// Called by QEMU with `argc` valid C strings in `argv`.
#[no_mangle]
pub unsafe extern "C" fn qemu_plugin_install(
    id: qemu_plugin_id_t,
    _info: *const qemu_info_t,
    argc: c_int,
    argv: *mut *mut c_char,
) -> c_int {
    for i in 0..usize::try_from(argc).unwrap_or(0) {
        let arg = CStr::from_ptr(*argv.add(i)).to_string_lossy();
        match arg.split_once('=') {
            Some(("out", path)) => match OpenOptions::new().create(true).append(true).open(path) {
                Ok(f) => {
                    if let Ok(mut state) = STATE.lock() {
                        state.out = Some(f);
                    }
                }
                Err(e) => {
                    eprintln!("insn-count: cannot open {path}: {e}");
                    return -1;
                }
            },
            Some(("profile", path)) => match File::create(path) {
                Ok(f) => {
                    if let Ok(mut state) = STATE.lock() {
                        state.profile = Some((f, HashMap::new(), HashMap::new()));
                    }
                }
                Err(e) => {
                    eprintln!("insn-count: cannot create {path}: {e}");
                    return -1;
                }
            },
            _ => {
                eprintln!("insn-count: unknown argument {arg} (expected out=FILE or profile=FILE)");
                return -1;
            }
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, Some(on_translate));
    qemu_plugin_register_atexit_cb(id, Some(on_exit), std::ptr::null_mut());
    0
}
