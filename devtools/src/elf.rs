//! Sizes and symbols of a 32-bit little-endian ELF firmware image (what the linker produced), read
//! with the `object` crate; symbol names demangled with `rustc-demangle`.

use anyhow::{Context, Result};
use object::elf::{SHF_ALLOC, SHF_WRITE, SHT_NOBITS, STT_FUNC};
use object::read::elf::{ElfFile32, SectionHeader, Sym};
use object::LittleEndian;
use std::path::Path;

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

/// The image as a 32-bit little-endian ELF file (what the Cortex-M linker writes).
fn parse(data: &[u8]) -> Result<ElfFile32<'_, LittleEndian>> {
    ElfFile32::parse(data).context("not a 32-bit little-endian ELF file")
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("reading {}", path.display()))
}

/// The value of the symbol `name` in the symbol table.
fn symbol(file: &ElfFile32<'_, LittleEndian>, name: &str) -> Result<u32> {
    let symbols = file.elf_symbol_table();
    for sym in symbols.iter() {
        if symbols.symbol_name(file.endian(), sym).ok() == Some(name.as_bytes()) {
            return Ok(sym.st_value(file.endian()));
        }
    }
    anyhow::bail!("symbol {name} not found (is this a cortex-m-rt image?)")
}

/// The address of the symbol `name` (an unmangled static, say) in the image at `path`.
pub fn symbol_address(path: &Path, name: &str) -> Result<u32> {
    let data = read(path)?;
    symbol(&parse(&data)?, name)
}

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
    let data = read(path)?;
    let file = parse(&data)?;
    let (endian, symbols) = (file.endian(), file.elf_symbol_table());
    let mut out = Vec::new();
    for sym in symbols.iter().filter(|s| s.st_type() == STT_FUNC) {
        let name = symbols
            .symbol_name(endian, sym)
            .context("bad symbol name")?;
        out.push(Function {
            addr: sym.st_value(endian) & !1,
            size: sym.st_size(endian),
            name: readable(&String::from_utf8_lossy(name)),
        });
    }
    out.sort_by_key(|f| f.addr);
    Ok(out)
}

/// A symbol as a Rust path without its hash (`{:#}`), legacy or v0 mangling; other names as
/// they are.
fn readable(name: &str) -> String {
    format!("{:#}", rustc_demangle::demangle(name))
}

/// Reads the footprint of the image at `path`.
pub fn footprint(path: &Path) -> Result<Footprint> {
    let data = read(path)?;
    let file = parse(&data)?;
    let endian = file.endian();
    let alloc = file
        .elf_section_table()
        .iter()
        .filter(|s| s.sh_flags(endian).0 & SHF_ALLOC.0 != 0);
    let flash_bytes = alloc
        .clone()
        .filter(|s| s.sh_type(endian) != SHT_NOBITS)
        .map(|s| u64::from(s.sh_size(endian)))
        .sum();
    let static_ram_bytes = alloc
        .filter(|s| s.sh_flags(endian).0 & SHF_WRITE.0 != 0)
        .map(|s| u64::from(s.sh_size(endian)))
        .sum();
    Ok(Footprint {
        flash_bytes,
        static_ram_bytes,
        stack_bottom: symbol(&file, "_stack_end")?,
        stack_top: symbol(&file, "_stack_start")?,
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
    fn demangles_rust_names_without_their_hash() {
        assert_eq!(
            readable("_ZN12planner_core3sqp5solve17h0123456789abcdefE"),
            "planner_core::sqp::solve"
        );
        assert_eq!(
            readable("_ZN12planner_core5seeds12sweep_pieces28_$u7b$$u7b$closure$u7d$$u7d$17h0123456789abcdefE"),
            "planner_core::seeds::sweep_pieces::{{closure}}"
        );
        assert_eq!(
            readable("_RNvNtCs7NhdfSRABLd_17compiler_builtins3mem6memcpy"),
            "compiler_builtins::mem::memcpy"
        );
        assert_eq!(readable("memcpy"), "memcpy");
    }

    #[test]
    fn rejects_what_is_not_an_elf32_file() {
        assert!(parse(b"not an elf").is_err());
    }
}
