//! Sizes and symbols of a 32-bit little-endian ELF firmware image (what the linker produced).

use anyhow::{bail, Context, Result};
use std::path::Path;

const SHT_SYMTAB: u32 = 2;
const SHT_NOBITS: u32 = 8;
const SHF_WRITE: u32 = 0x1;
const SHF_ALLOC: u32 = 0x2;

/// What the image costs in memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Footprint {
    /// Bytes programmed into flash: vector table, code, read-only data and the initial values of
    /// `.data` (every allocated section with contents).
    pub flash_bytes: u64,
    /// Statically allocated RAM: `.data`, `.bss` and `.uninit` (every allocated writable section).
    pub static_ram_bytes: u64,
    /// The stack: painted and measured between these addresses (`_stack_end` .. `_stack_start`).
    pub stack_bottom: u32,
    /// Initial stack pointer.
    pub stack_top: u32,
}

struct Section {
    kind: u32,
    flags: u32,
    offset: usize,
    size: usize,
    link: usize,
}

fn u16_at(b: &[u8], at: usize) -> Result<u16> {
    let s = b.get(at..at + 2).context("ELF truncated")?;
    Ok(u16::from_le_bytes([s[0], s[1]]))
}

fn u32_at(b: &[u8], at: usize) -> Result<u32> {
    let s = b.get(at..at + 4).context("ELF truncated")?;
    Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

fn sections(b: &[u8]) -> Result<Vec<Section>> {
    if b.get(..6) != Some(&[0x7f, b'E', b'L', b'F', 1, 1][..]) {
        bail!("not a 32-bit little-endian ELF file");
    }
    let shoff = u32_at(b, 0x20)? as usize;
    let shentsize = usize::from(u16_at(b, 0x2E)?);
    let shnum = usize::from(u16_at(b, 0x30)?);
    (0..shnum)
        .map(|i| {
            let h = shoff + i * shentsize;
            Ok(Section {
                kind: u32_at(b, h + 4)?,
                flags: u32_at(b, h + 8)?,
                offset: u32_at(b, h + 16)? as usize,
                size: u32_at(b, h + 20)? as usize,
                link: u32_at(b, h + 24)? as usize,
            })
        })
        .collect()
}

fn symbol(b: &[u8], sections: &[Section], name: &str) -> Result<u32> {
    for symtab in sections.iter().filter(|s| s.kind == SHT_SYMTAB) {
        let strtab = sections
            .get(symtab.link)
            .context("symbol table without strings")?;
        for entry in (symtab.offset..symtab.offset + symtab.size).step_by(16) {
            let name_at = strtab.offset + u32_at(b, entry)? as usize;
            let end = b[name_at..]
                .iter()
                .position(|&c| c == 0)
                .context("bad symbol name")?;
            if &b[name_at..name_at + end] == name.as_bytes() {
                return u32_at(b, entry + 4);
            }
        }
    }
    bail!("symbol {name} not found (is this a cortex-m-rt image?)")
}

const STT_FUNC: u8 = 2;

/// A function of the image: start address (Thumb bit cleared), size, demangled path.
pub struct Function {
    /// First byte.
    pub addr: u32,
    /// Bytes.
    pub size: u32,
    /// Readable name.
    pub name: String,
}

/// The image's functions, sorted by address.
pub fn functions(path: &Path) -> Result<Vec<Function>> {
    let b = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let sections = sections(&b)?;
    let mut out = Vec::new();
    for symtab in sections.iter().filter(|s| s.kind == SHT_SYMTAB) {
        let strtab = sections
            .get(symtab.link)
            .context("symbol table without strings")?;
        for entry in (symtab.offset..symtab.offset + symtab.size).step_by(16) {
            if b.get(entry + 12).map(|i| i & 0xF) != Some(STT_FUNC) {
                continue;
            }
            let name_at = strtab.offset + u32_at(&b, entry)? as usize;
            let end = b[name_at..]
                .iter()
                .position(|&c| c == 0)
                .context("bad symbol name")?;
            out.push(Function {
                addr: u32_at(&b, entry + 4)? & !1,
                size: u32_at(&b, entry + 8)?,
                name: demangle(&String::from_utf8_lossy(&b[name_at..name_at + end])),
            });
        }
    }
    out.sort_by_key(|f| f.addr);
    Ok(out)
}

/// Legacy Rust mangling (`_ZN` length-prefixed parts, a trailing hash) to `a::b::c`.
fn demangle(name: &str) -> String {
    let Some(mut rest) = name.strip_prefix("_ZN") else {
        return name.to_owned();
    };
    let mut parts = Vec::new();
    while let Some(digits) = rest.find(|c: char| !c.is_ascii_digit()).filter(|&d| d > 0) {
        let Ok(len) = rest[..digits].parse::<usize>() else {
            break;
        };
        let Some(part) = rest.get(digits..digits + len) else {
            break;
        };
        parts.push(
            part.replace("$LT$", "<")
                .replace("$GT$", ">")
                .replace("$u20$", " ")
                .replace("..", "::"),
        );
        rest = &rest[digits + len..];
    }
    if parts
        .last()
        .is_some_and(|p| p.len() == 17 && p.starts_with('h'))
    {
        parts.pop();
    }
    if parts.is_empty() {
        name.to_owned()
    } else {
        parts.join("::")
    }
}

/// Reads the footprint of the image at `path`.
pub fn footprint(path: &Path) -> Result<Footprint> {
    let b = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let sections = sections(&b)?;
    let alloc = sections.iter().filter(|s| s.flags & SHF_ALLOC != 0);
    let flash_bytes = alloc
        .clone()
        .filter(|s| s.kind != SHT_NOBITS)
        .map(|s| s.size as u64)
        .sum();
    let static_ram_bytes = alloc
        .filter(|s| s.flags & SHF_WRITE != 0)
        .map(|s| s.size as u64)
        .sum();
    Ok(Footprint {
        flash_bytes,
        static_ram_bytes,
        stack_bottom: symbol(&b, &sections, "_stack_end")?,
        stack_top: symbol(&b, &sections, "_stack_start")?,
    })
}

/// Bytes of stack used at the deepest: the distance from the stack top down to the lowest word
/// that no longer holds the paint (`memory` starts at `footprint.stack_bottom`).
pub fn peak_stack(memory: &[u8], paint: u32) -> u64 {
    let words = memory.len() / 4;
    let untouched = memory
        .chunks_exact(4)
        .take_while(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) == paint)
        .count();
    ((words - untouched) * 4) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_stack_counts_from_the_first_scrubbed_word() {
        let paint = 0xCCCC_CCCCu32;
        let mut mem: Vec<u8> = std::iter::repeat_n(paint.to_le_bytes(), 8)
            .flatten()
            .collect();
        assert_eq!(peak_stack(&mem, paint), 0);
        mem[13] = 0; // word 3 scrubbed: words 3..8 were used
        assert_eq!(peak_stack(&mem, paint), 20);
    }

    #[test]
    fn demangles_legacy_rust_names() {
        assert_eq!(
            demangle("_ZN12planner_core3sqp5solve17h0123456789abcdefE"),
            "planner_core::sqp::solve"
        );
        assert_eq!(demangle("memcpy"), "memcpy");
    }

    #[test]
    fn rejects_what_is_not_an_elf32_file() {
        assert!(sections(b"not an elf").is_err());
    }
}
