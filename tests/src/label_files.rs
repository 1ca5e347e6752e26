//! Label maps written as files for the cover tests: NRRD (raw or gzip, LPS or RAS, with
//! Slicer's segment names) and NIfTI-1 (sform), written here byte by byte from the formats'
//! specifications, so the readers are checked against files they did not write.

use serde_json::Value;
use std::io::Write;
use std::path::Path;

/// A label map to write: `labels[i + nx (j + ny k)]`, the voxel-to-RAS affine's rows.
pub struct Labels {
    /// Voxels along i, j, k.
    pub dims: [usize; 3],
    /// One label per voxel, i fastest.
    pub labels: Vec<i16>,
    /// Rows of the voxel-to-RAS affine (mm).
    pub ijk_to_ras: [[f64; 4]; 3],
}

impl Labels {
    /// The map whose label at (i, j, k) is `f(i, j, k)`.
    pub fn of(
        dims: [usize; 3],
        ijk_to_ras: [[f64; 4]; 3],
        f: impl Fn(i64, i64, i64) -> i16,
    ) -> Labels {
        let mut labels = Vec::new();
        for k in 0..dims[2] as i64 {
            for j in 0..dims[1] as i64 {
                for i in 0..dims[0] as i64 {
                    labels.push(f(i, j, k));
                }
            }
        }
        Labels {
            dims,
            labels,
            ijk_to_ras,
        }
    }
}

/// How a NRRD file is written.
pub struct NrrdStyle<'a> {
    /// "left-posterior-superior" (the coordinates are converted) or "right-anterior-superior".
    pub space: &'a str,
    /// gzip the data.
    pub gzip: bool,
    /// Key-value pairs (`key:=value`), e.g. Slicer's segment names.
    pub pairs: &'a [(&'a str, &'a str)],
}

/// Writes `m` as NRRD (int16, little-endian).
pub fn write_nrrd(path: &Path, m: &Labels, style: &NrrdStyle) {
    let lps = style.space == "left-posterior-superior";
    let flip = if lps { [-1.0, -1.0, 1.0] } else { [1.0; 3] };
    let a = &m.ijk_to_ras;
    let col = |c: usize| {
        format!(
            "({},{},{})",
            flip[0] * a[0][c],
            flip[1] * a[1][c],
            flip[2] * a[2][c]
        )
    };
    let mut text = format!(
        "NRRD0004\n# written by the needle-planner tests\ntype: short\ndimension: 3\nspace: {}\n\
         sizes: {} {} {}\nspace directions: {} {} {}\nkinds: domain domain domain\nendian: little\n\
         encoding: {}\nspace origin: ({},{},{})\n",
        style.space,
        m.dims[0],
        m.dims[1],
        m.dims[2],
        col(0),
        col(1),
        col(2),
        if style.gzip { "gzip" } else { "raw" },
        flip[0] * a[0][3],
        flip[1] * a[1][3],
        flip[2] * a[2][3],
    );
    for (k, v) in style.pairs {
        text += &format!("{k}:={v}\n");
    }
    text += "\n";
    let raw: Vec<u8> = m.labels.iter().flat_map(|l| l.to_le_bytes()).collect();
    let mut bytes = text.into_bytes();
    if style.gzip {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&raw).unwrap();
        bytes.extend(gz.finish().unwrap());
    } else {
        bytes.extend(raw);
    }
    std::fs::write(path, bytes).unwrap();
}

/// Writes `m` as NIfTI-1 (`.nii`, int16, the affine as the sform, millimetres).
pub fn write_nifti(path: &Path, m: &Labels) {
    let mut h = vec![0u8; 352];
    let put = |h: &mut Vec<u8>, at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(&mut h, 0, &348i32.to_le_bytes());
    put(&mut h, 38, b"r");
    let dim: [i16; 8] = [
        3,
        m.dims[0] as i16,
        m.dims[1] as i16,
        m.dims[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for (k, d) in dim.iter().enumerate() {
        put(&mut h, 40 + 2 * k, &d.to_le_bytes());
    }
    put(&mut h, 70, &4i16.to_le_bytes()); // int16
    put(&mut h, 72, &16i16.to_le_bytes());
    let spacing = [0, 1, 2].map(|c| {
        (0..3)
            .map(|r| m.ijk_to_ras[r][c].powi(2))
            .sum::<f64>()
            .sqrt() as f32
    });
    let pixdim = [
        1.0, spacing[0], spacing[1], spacing[2], 1.0, 1.0, 1.0, 1.0f32,
    ];
    for (k, p) in pixdim.iter().enumerate() {
        put(&mut h, 76 + 4 * k, &p.to_le_bytes());
    }
    put(&mut h, 108, &352f32.to_le_bytes());
    put(&mut h, 112, &1f32.to_le_bytes());
    put(&mut h, 123, &[2]); // millimetres
    put(&mut h, 254, &1i16.to_le_bytes()); // sform_code: scanner
    for (r, row) in m.ijk_to_ras.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(&mut h, 280 + 16 * r + 4 * c, &(*v as f32).to_le_bytes());
        }
    }
    put(&mut h, 344, b"n+1\0");
    h.extend(m.labels.iter().flat_map(|l| l.to_le_bytes()));
    std::fs::write(path, h).unwrap();
}

/// Writes a binary STL of the box `lo`–`hi` (12 triangles, outward), `header` in its 80-byte
/// header (3D Slicer writes `SPACE=RAS` or `SPACE=LPS` there); `drop_face` leaves one side open.
pub fn write_stl_box(path: &Path, lo: [f32; 3], hi: [f32; 3], header: &str, drop_face: bool) {
    let c = |i: usize| [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
    // Two triangles per side, each side's corners in order around it.
    let sides: [[usize; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut tris = Vec::new();
    for s in sides.iter().skip(usize::from(drop_face)) {
        tris.push([c(s[0]), c(s[1]), c(s[2])]);
        tris.push([c(s[0]), c(s[2]), c(s[3])]);
    }
    let mut bytes = vec![0u8; 80];
    bytes[..header.len()].copy_from_slice(header.as_bytes());
    bytes.extend((tris.len() as u32).to_le_bytes());
    for t in &tris {
        bytes.extend([0f32; 3].iter().flat_map(|x| x.to_le_bytes()));
        for v in t {
            bytes.extend(v.iter().flat_map(|x| x.to_le_bytes()));
        }
        bytes.extend([0u8; 2]);
    }
    std::fs::write(path, bytes).unwrap();
}

/// The spheres of a `needle cover --json` report, in its order: (label, centre, radius).
pub fn cover_spheres(report: &Value) -> Vec<(i64, [f64; 3], f64)> {
    let mut out = Vec::new();
    for seg in report["segments"].as_array().expect("segments") {
        for s in seg["spheres"].as_array().expect("spheres") {
            let c: Vec<f64> = s["center"]
                .as_array()
                .expect("center")
                .iter()
                .map(|x| x.as_f64().expect("a number"))
                .collect();
            out.push((
                seg["label"].as_i64().expect("a label"),
                [c[0], c[1], c[2]],
                s["radius"].as_f64().expect("a radius"),
            ));
        }
    }
    out
}
