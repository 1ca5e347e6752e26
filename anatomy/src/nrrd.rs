//! NRRD label maps (teem's format, which 3D Slicer writes as `.nrrd` and `.seg.nrrd`).
//!
//! No maintained Rust crate reads NRRD: its header is text and its data raw or gzip, so this is
//! a small reader (flate2 for gzip). Read: `type`, `dimension` 3, `sizes`, `encoding` raw or
//! gzip, `endian`, `space` (LPS and RAS, and their long names), `space directions`,
//! `space origin`, and Slicer's `SegmentN_Name` / `SegmentN_LabelValue` key-value pairs.
//! Coordinates in LPS are turned into RAS (x and y negated).

use super::label_map::{whole_label, LabelMap, Segment};
use anyhow::{anyhow, bail, Context, Result};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// The bytes of each sample type NRRD names, and whether it is signed or a float.
fn sample_type(name: &str) -> Option<(usize, char)> {
    Some(match name {
        "signed char" | "int8" | "int8_t" => (1, 'i'),
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => (1, 'u'),
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            (2, 'i')
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => (2, 'u'),
        "int" | "signed int" | "int32" | "int32_t" => (4, 'i'),
        "uint" | "unsigned int" | "uint32" | "uint32_t" => (4, 'u'),
        "longlong" | "long long" | "long long int" | "signed long long" | "int64" | "int64_t" => {
            (8, 'i')
        }
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            (8, 'u')
        }
        "float" => (4, 'f'),
        "double" => (8, 'f'),
        _ => return None,
    })
}

/// The header's fields (lower-cased keys) and key-value pairs, and where the data starts.
struct Header {
    fields: BTreeMap<String, String>,
    pairs: BTreeMap<String, String>,
    data_at: usize,
}

fn header(bytes: &[u8]) -> Result<Header> {
    if !bytes.starts_with(b"NRRD000") {
        bail!("not a NRRD file (it does not start with \"NRRD000\")");
    }
    let mut fields = BTreeMap::new();
    let mut pairs = BTreeMap::new();
    let mut at = 0usize;
    let mut first = true;
    loop {
        let Some(end) = bytes[at..].iter().position(|&b| b == b'\n') else {
            bail!("the header never ends (no blank line before the data)");
        };
        let line = std::str::from_utf8(&bytes[at..at + end])
            .map_err(|_| anyhow!("the header is not text"))?
            .trim_end_matches('\r');
        at += end + 1;
        if first {
            first = false;
            continue;
        }
        if line.is_empty() {
            break;
        }
        if line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once(":=") {
            pairs.insert(k.trim().to_string(), v.trim().to_string());
        } else if let Some((k, v)) = line.split_once(": ") {
            fields.insert(k.trim().to_lowercase(), v.trim().to_string());
        } else {
            bail!("the header line {line:?} is neither a field nor a key-value pair");
        }
    }
    Ok(Header {
        fields,
        pairs,
        data_at: at,
    })
}

/// A vector written `(x,y,z)`.
fn vector(s: &str) -> Result<[f64; 3]> {
    let inner = s
        .trim()
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| anyhow!("{s:?} is not a vector (x,y,z)"))?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow!("{s:?} is not a vector of numbers"))?;
    match v[..] {
        [x, y, z] => Ok([x, y, z]),
        _ => bail!("{s:?} has {} components, not 3", v.len()),
    }
}

/// Reads a NRRD label map.
pub fn read(path: &Path) -> Result<LabelMap> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse(&bytes).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// Parses the bytes of a NRRD file.
pub fn parse(bytes: &[u8]) -> Result<LabelMap> {
    let h = header(bytes)?;
    let field = |k: &str| {
        h.fields
            .get(k)
            .map(String::as_str)
            .ok_or_else(|| anyhow!("the header has no {k:?} field"))
    };
    if h.fields.contains_key("data file") || h.fields.contains_key("datafile") {
        bail!("the data is in a detached file: save the map as one .nrrd");
    }
    if field("dimension")?.trim() != "3" {
        bail!(
            "dimension {} is not a 3-D label map (a segmentation with overlapping layers has 4: \
             export it as a label map)",
            field("dimension")?
        );
    }
    let sizes: Vec<usize> = field("sizes")?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow!("the sizes are not whole numbers"))?;
    let dims: [usize; 3] = sizes.try_into().map_err(|_| anyhow!("3 sizes expected"))?;
    let (width, kind) = sample_type(field("type")?)
        .ok_or_else(|| anyhow!("unknown type {:?}", h.fields["type"]))?;
    let big = width > 1 && big_endian(h.fields.get("endian"))?;
    let raw = &bytes[h.data_at..];
    let data = match field("encoding")? {
        "raw" => raw.to_vec(),
        "gzip" | "gz" => {
            let mut out = Vec::new();
            flate2::read::GzDecoder::new(raw)
                .read_to_end(&mut out)
                .map_err(|e| anyhow!("the gzip data cannot be read: {e}"))?;
            out
        }
        other => bail!("encoding {other:?} is not read (raw and gzip are)"),
    };
    let n = dims.iter().product::<usize>();
    let need = n
        .checked_mul(width)
        .ok_or_else(|| anyhow!("sizes too large"))?;
    if data.len() < need {
        bail!("the data has {} bytes, the sizes need {need}", data.len());
    }
    let labels = data[..need]
        .chunks_exact(width)
        .map(|c| sample(c, kind, big))
        .collect::<Result<Vec<i64>>>()?;
    Ok(LabelMap {
        dims,
        labels,
        ijk_to_ras: placement(&h)?,
        named: segments(&h.pairs)?,
    })
}

/// Whether the `endian` field says big-endian (in any case, as teem reads it); little when
/// absent. Any other word is refused rather than guessed.
fn big_endian(field: Option<&String>) -> Result<bool> {
    match field.map(|e| e.trim().to_lowercase()).as_deref() {
        None | Some("little") => Ok(false),
        Some("big") => Ok(true),
        Some(_) => bail!(
            "endian {:?} is neither big nor little",
            field.map_or("", String::as_str)
        ),
    }
}

/// One sample as a label: integers as they are, floats only when whole.
fn sample(c: &[u8], kind: char, big: bool) -> Result<i64> {
    let mut b = [0u8; 8];
    let w = c.len();
    if big {
        for (k, v) in c.iter().rev().enumerate() {
            b[k] = *v;
        }
    } else {
        b[..w].copy_from_slice(c);
    }
    let u = u64::from_le_bytes(b);
    Ok(match (kind, w) {
        ('u', _) => i64::try_from(u).map_err(|_| anyhow!("a label over 2^63"))?,
        ('i', 8) => u as i64,
        ('i', _) => {
            let shift = 64 - 8 * w as u32;
            ((u << shift) as i64) >> shift
        }
        (_, 4) => whole_label(f64::from(f32::from_bits(u as u32)))?,
        _ => whole_label(f64::from_bits(u))?,
    })
}

/// The voxel-to-RAS affine from `space`, `space directions` and `space origin`.
fn placement(h: &Header) -> Result<[[f64; 4]; 3]> {
    let Some(dirs) = h.fields.get("space directions") else {
        bail!("the header has no \"space directions\": the map's place in the world is unknown");
    };
    let cols: Vec<[f64; 3]> = dirs
        .split(')')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| vector(&format!("{s})")))
        .collect::<Result<_>>()?;
    let cols: [[f64; 3]; 3] = cols
        .try_into()
        .map_err(|_| anyhow!("\"space directions\" must give 3 vectors"))?;
    let origin = match h.fields.get("space origin") {
        Some(o) => vector(o)?,
        None => [0.0; 3],
    };
    let space = h.fields.get("space").map(|s| s.to_lowercase());
    let flip = match space.as_deref() {
        Some("left-posterior-superior" | "lps") => [-1.0, -1.0, 1.0],
        Some("right-anterior-superior" | "ras") => [1.0, 1.0, 1.0],
        Some(other) => bail!("space {other:?} is not read (LPS and RAS are)"),
        None => bail!("the header has no \"space\": LPS or RAS is unknown"),
    };
    let mut a = [[0.0; 4]; 3];
    for r in 0..3 {
        for (c, col) in cols.iter().enumerate() {
            a[r][c] = flip[r] * col[r];
        }
        a[r][3] = flip[r] * origin[r];
    }
    Ok(a)
}

/// Slicer's segment names and label values (`SegmentN_Name`, `SegmentN_LabelValue`).
fn segments(pairs: &BTreeMap<String, String>) -> Result<Vec<Segment>> {
    let mut out = Vec::new();
    for n in 0.. {
        let (Some(name), label) = (
            pairs.get(&format!("Segment{n}_Name")),
            pairs.get(&format!("Segment{n}_LabelValue")),
        ) else {
            break;
        };
        let label = match label {
            Some(l) => l
                .parse()
                .map_err(|_| anyhow!("Segment{n}_LabelValue {l:?} is not a whole number"))?,
            None => n + 1,
        };
        out.push(Segment {
            name: name.clone(),
            label,
        });
    }
    Ok(out)
}
