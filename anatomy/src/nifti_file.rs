//! NIfTI-1 label maps (`.nii`, `.nii.gz`), read with the `nifti` crate. The world frame of NIfTI
//! is RAS already; the affine is the sform when its code is set, else the qform, else the voxel
//! sizes alone (the format's "method 1"), computed here from the header's fields (the crate's own
//! qform affine panics on some headers).

use super::label_map::{whole_label, LabelMap};
use anyhow::{anyhow, bail, Result};
use nifti::{NiftiError, NiftiHeader, NiftiObject, NiftiType, ReaderOptions};
use std::path::Path;

/// The `nifti` crate's error in words: its I/O errors print as Rust debug text.
fn words(e: &NiftiError) -> String {
    match e {
        NiftiError::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file ends before its data does (truncated?)".into()
        }
        NiftiError::Io(io) => io.to_string(),
        other => other.to_string(),
    }
}

/// Reads a NIfTI label map.
pub fn read(path: &Path) -> Result<LabelMap> {
    let at = |e: anyhow::Error| anyhow!("{}: {e}", path.display());
    let bytes = std::fs::read(path).map_err(|e| anyhow!("cannot read {}: {e}", path.display()))?;
    let gz = bytes.starts_with(&[0x1f, 0x8b]);
    let magic_ok =
        |b: &[u8]| b.len() >= 348 && (&b[344..348] == b"n+1\0" || &b[344..348] == b"ni1\0");
    if !gz && !magic_ok(&bytes) {
        return Err(at(anyhow!("not a NIfTI-1 file (no \"n+1\" magic)")));
    }
    let obj = ReaderOptions::new()
        .read_file(path)
        .map_err(|e| at(anyhow!("not a NIfTI-1 file this reads: {}", words(&e))))?;
    let h = obj.header().clone();
    let dims = dims(&h).map_err(at)?;
    let labels = labels(obj.into_volume(), &h).map_err(at)?;
    Ok(LabelMap {
        dims,
        labels,
        ijk_to_ras: affine(&h).map_err(at)?,
        named: Vec::new(),
    })
}

fn dims(h: &NiftiHeader) -> Result<[usize; 3]> {
    let rank = usize::from(h.dim[0]);
    if !(1..=7).contains(&rank) {
        bail!("dim[0] = {rank} is not a rank from 1 to 7");
    }
    if h.dim[4..=rank.max(3)].iter().any(|&d| d > 1) {
        bail!("a {rank}-D volume with more than one 3-D frame is not a label map");
    }
    Ok([1, 2, 3].map(|k| if k <= rank { usize::from(h.dim[k]) } else { 1 }))
}

fn labels(volume: nifti::InMemNiftiVolume, h: &NiftiHeader) -> Result<Vec<i64>> {
    let t = h.data_type().map_err(|e| anyhow!("{}", words(&e)))?;
    let ints: Vec<i64> = match t {
        NiftiType::Uint8 => widen(volume.into_nifti_typed_data::<u8>()),
        NiftiType::Int8 => widen(volume.into_nifti_typed_data::<i8>()),
        NiftiType::Uint16 => widen(volume.into_nifti_typed_data::<u16>()),
        NiftiType::Int16 => widen(volume.into_nifti_typed_data::<i16>()),
        NiftiType::Uint32 => widen(volume.into_nifti_typed_data::<u32>()),
        NiftiType::Int32 => widen(volume.into_nifti_typed_data::<i32>()),
        NiftiType::Int64 => volume
            .into_nifti_typed_data::<i64>()
            .map_err(|e| anyhow!("{}", words(&e))),
        NiftiType::Float32 => floats(
            volume
                .into_nifti_typed_data::<f32>()
                .map(|v| v.into_iter().map(f64::from).collect()),
        ),
        NiftiType::Float64 => floats(volume.into_nifti_typed_data::<f64>()),
        other => bail!(
            "data type {} is not a label type",
            format!("{other:?}").to_lowercase()
        ),
    }?;
    // A scaled map holds labels only if slope and intercept keep them whole.
    let (slope, inter) = (f64::from(h.scl_slope), f64::from(h.scl_inter));
    if slope == 0.0 || (slope == 1.0 && inter == 0.0) {
        return Ok(ints);
    }
    ints.into_iter()
        .map(|v| whole_label(v as f64 * slope + inter))
        .collect()
}

fn widen<T: Into<i64>>(v: nifti::Result<Vec<T>>) -> Result<Vec<i64>> {
    Ok(v.map_err(|e| anyhow!("{}", words(&e)))?
        .into_iter()
        .map(Into::into)
        .collect())
}

fn floats(v: nifti::Result<Vec<f64>>) -> Result<Vec<i64>> {
    v.map_err(|e| anyhow!("{}", words(&e)))?
        .into_iter()
        .map(whole_label)
        .collect()
}

/// Millimetres per unit of the header's spatial unit.
fn unit_mm(h: &NiftiHeader) -> f64 {
    match h.xyzt_units & 7 {
        1 => 1000.0,
        3 => 0.001,
        _ => 1.0,
    }
}

fn affine(h: &NiftiHeader) -> Result<[[f64; 4]; 3]> {
    let mm = unit_mm(h);
    let mut a = [[0.0; 4]; 3];
    if h.sform_code > 0 {
        for (r, row) in [h.srow_x, h.srow_y, h.srow_z].iter().enumerate() {
            for c in 0..4 {
                a[r][c] = f64::from(row[c]) * mm;
            }
        }
    } else if h.qform_code > 0 {
        let (b, c, d) = (
            f64::from(h.quatern_b),
            f64::from(h.quatern_c),
            f64::from(h.quatern_d),
        );
        let a0 = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = [
            [
                a0 * a0 + b * b - c * c - d * d,
                2.0 * (b * c - a0 * d),
                2.0 * (b * d + a0 * c),
            ],
            [
                2.0 * (b * c + a0 * d),
                a0 * a0 + c * c - b * b - d * d,
                2.0 * (c * d - a0 * b),
            ],
            [
                2.0 * (b * d - a0 * c),
                2.0 * (c * d + a0 * b),
                a0 * a0 + d * d - c * c - b * b,
            ],
        ];
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let step = [
            f64::from(h.pixdim[1]),
            f64::from(h.pixdim[2]),
            f64::from(h.pixdim[3]) * qfac,
        ];
        let offset = [h.quatern_x, h.quatern_y, h.quatern_z].map(f64::from);
        for row in 0..3 {
            for col in 0..3 {
                a[row][col] = r[row][col] * step[col] * mm;
            }
            a[row][3] = offset[row] * mm;
        }
    } else {
        for (k, row) in a.iter_mut().enumerate() {
            row[k] = f64::from(h.pixdim[k + 1]) * mm;
        }
    }
    Ok(a)
}
