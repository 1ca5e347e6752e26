//! Marker instructions that delimit measured work for the QEMU instruction-count plugin
//! (`tools/insn-count`).
//!
//! Each marker is a 16-bit `mov rX, rX` the compiler never emits on its own: it changes nothing on
//! the device and costs one cycle, so the flashed firmware is the measured firmware. The plugin sums
//! the instructions executed between `begin` and `end`, and prints the sum at `report`.

/// Starts a measured region (`mov r10, r10` = 0x46D2).
#[inline(always)]
pub fn begin() {
    // SAFETY: a register move onto itself; no memory, stack or flags are touched. Not marked
    // `nomem`, so the compiler keeps memory accesses on their side of the marker.
    unsafe { core::arch::asm!("mov r10, r10", options(nostack, preserves_flags)) }
}

/// Ends a measured region (`mov r11, r11` = 0x46DB).
#[inline(always)]
pub fn end() {
    // SAFETY: as for `begin`.
    unsafe { core::arch::asm!("mov r11, r11", options(nostack, preserves_flags)) }
}

/// Reports and resets the sum of the regions since the last report (`mov r12, r12` = 0x46E4).
#[inline(always)]
pub fn report() {
    // SAFETY: as for `begin`.
    unsafe { core::arch::asm!("mov r12, r12", options(nostack, preserves_flags)) }
}
