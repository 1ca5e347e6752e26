//! Closed surface meshes (STL, binary or ASCII, through the `stl_io` crate; Wavefront OBJ
//! through `tobj`) as the solid they bound, voxelised into a label map that the cover then
//! covers.
//!
//! The voxelisation is conservative: a voxel is in the solid when its centre is inside (a ray
//! along +x counts the crossings of the surface) or when the box of any triangle overlaps it.
//! A voxel holding a point of the solid but not its centre holds a point of the surface too, so
//! every point of the solid lies in a marked voxel, and the cover, which holds every marked
//! voxel whole, holds the solid. Coordinates: RAS when the file says `SPACE=RAS` (3D Slicer
//! writes that in its header), else LPS, the system Slicer assumes for a mesh that names none.

use super::label_map::{LabelMap, Segment};
use anyhow::{anyhow, bail, Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// The edge of a voxel when none is given (mm).
pub const DEFAULT_VOXEL_MM: f64 = 0.5;

/// The largest voxel a mesh is voxelised at (mm): coarser, the cover says little of the shape.
pub const MAX_VOXEL_MM: f64 = 10.0;

/// The most voxels a mesh's grid may have.
const MAX_VOXELS: usize = 64_000_000;

/// The extents (mm) a mesh in millimetres plausibly has: an anatomical structure is more than a
/// millimetre across and less than two metres. A mesh in metres is a thousandth of that.
const PLAUSIBLE_MM: (f64, f64) = (1.0, 2000.0);

/// Millimetres per `unit`.
fn unit_mm(unit: &str) -> Result<f64> {
    Ok(match unit {
        "mm" => 1.0,
        "cm" => 10.0,
        "m" => 1000.0,
        "um" => 0.001,
        other => bail!("the unit {other:?} is none of mm, cm, m, um"),
    })
}

/// Reads the closed mesh `path` as a label map (label 1, named after the file) of voxels
/// `voxel_mm` across; its coordinates are in `unit` (see [`unit_mm`]), or millimetres when
/// `None`, and then a mesh whose extent is implausible for millimetres is refused.
pub fn read(path: &Path, voxel_mm: f64, unit: Option<&str>) -> Result<LabelMap> {
    if !(voxel_mm > 0.0 && voxel_mm <= MAX_VOXEL_MM) {
        bail!("the voxel size must be above 0 and at most {MAX_VOXEL_MM} mm, not {voxel_mm}");
    }
    let scale = unit.map(unit_mm).transpose()?;
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(256)]).to_string();
    let ras = head.contains("SPACE=RAS");
    let obj = path.to_string_lossy().to_lowercase().ends_with(".obj");
    let (points, faces) = if obj {
        obj_mesh(path)?
    } else {
        stl_mesh(&bytes)?
    };
    if faces.is_empty() {
        bail!("the mesh has no triangles");
    }
    let flip = if ras {
        [1.0, 1.0, 1.0]
    } else {
        [-1.0, -1.0, 1.0]
    };
    let mm = scale.unwrap_or(1.0);
    let points: Vec<[f64; 3]> = points
        .iter()
        .map(|v| [0, 1, 2].map(|k| flip[k] * v[k] * mm))
        .collect();
    if points.iter().flatten().any(|c| !c.is_finite()) {
        bail!("the mesh has a vertex that is not finite");
    }
    if scale.is_none() {
        plausible_in_mm(&points)?;
    }
    // Vertices at the same place are one vertex (a file may repeat them).
    let mut welded: BTreeMap<[u64; 3], usize> = BTreeMap::new();
    let ids: Vec<usize> = points
        .iter()
        .map(|p| {
            let n = welded.len();
            *welded.entry(p.map(f64::to_bits)).or_insert(n)
        })
        .collect();
    let mut faces_welded = Vec::with_capacity(faces.len());
    for f in &faces {
        if f.iter().any(|&i| i >= points.len()) {
            bail!("a triangle refers to a vertex the mesh does not have");
        }
        faces_welded.push(f.map(|i| ids[i]));
    }
    closed(&faces_welded)?;
    let triangles: Vec<[[f64; 3]; 3]> = faces.iter().map(|f| f.map(|i| points[i])).collect();
    voxelise(&triangles, voxel_mm, path)
}

/// Refuses a mesh whose largest extent is implausible for millimetres (a mesh saved in metres
/// would be covered as a speck, and a plan would pass where the structure is).
fn plausible_in_mm(points: &[[f64; 3]]) -> Result<()> {
    let extent = (0..3)
        .map(|k| {
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(p[k]), h.max(p[k]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    let (lo, hi) = PLAUSIBLE_MM;
    if extent < lo {
        bail!(
            "the mesh is {extent} across, implausible for millimetres (a mesh saved in metres?): \
             give its unit (--unit m, or unit = \"m\" in [[anatomy]]; or mm if it is that small)"
        );
    }
    if extent > hi {
        bail!(
            "the mesh is {extent} across, implausible for millimetres (a mesh saved in \
             micrometres?): give its unit (--unit um, or unit = \"um\" in [[anatomy]]; or mm)"
        );
    }
    Ok(())
}

/// A mesh as read: its vertices and its triangles (indices into them).
type Triangles = (Vec<[f64; 3]>, Vec<[usize; 3]>);

/// The vertices and triangles of an STL file's bytes.
fn stl_mesh(bytes: &[u8]) -> Result<Triangles> {
    let mesh = stl_io::read_stl(&mut std::io::Cursor::new(bytes))
        .map_err(|e| anyhow!("not an STL mesh this reads: {e}"))?;
    let points = mesh.vertices.iter().map(|v| v.0.map(f64::from)).collect();
    Ok((points, mesh.faces.iter().map(|f| f.vertices).collect()))
}

/// The vertices and triangles (polygons fanned) of every object of an OBJ file.
fn obj_mesh(path: &Path) -> Result<Triangles> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ..Default::default()
    };
    let (models, _materials) =
        tobj::load_obj(path, &options).map_err(|e| anyhow!("not an OBJ mesh this reads: {e}"))?;
    let (mut points, mut faces) = (Vec::new(), Vec::new());
    for m in &models {
        let base = points.len();
        points.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]),
        );
        faces.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [0, 1, 2].map(|k| base + t[k] as usize)),
        );
    }
    Ok((points, faces))
}

/// Every edge bounds exactly two triangles.
fn closed(faces: &[[usize; 3]]) -> Result<()> {
    let mut edges: BTreeMap<(usize, usize), u32> = BTreeMap::new();
    for &v in faces {
        for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let open = edges.values().filter(|&&n| n != 2).count();
    if open > 0 {
        bail!(
            "the mesh is not closed ({open} of its {} edges do not bound exactly two triangles): \
             a cover needs the solid a closed surface bounds",
            edges.len()
        );
    }
    Ok(())
}

fn voxelise(triangles: &[[[f64; 3]; 3]], h: f64, path: &Path) -> Result<LabelMap> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in triangles.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    // One voxel of room on each side; voxel centres at lo - h + i·h.
    let origin = lo.map(|x| x - h);
    let dims = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / h).ceil() as usize + 3);
    let count = dims[0]
        .checked_mul(dims[1])
        .and_then(|n| n.checked_mul(dims[2]))
        .filter(|&n| n <= MAX_VOXELS)
        .ok_or_else(|| {
            anyhow!("the mesh spans more than {MAX_VOXELS} voxels of {h} mm: give a larger voxel")
        })?;
    let mut labels = vec![0i64; count];
    let index = |g: [usize; 3]| g[0] + dims[0] * (g[1] + dims[1] * g[2]);
    let cell =
        |x: f64, k: usize| (((x - origin[k]) / h).round().max(0.0) as usize).min(dims[k] - 1);
    // The voxels each triangle's box overlaps.
    for t in triangles {
        let (a, b) = (
            [0, 1, 2].map(|k| cell(t.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min), k)),
            [0, 1, 2].map(|k| cell(t.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max), k)),
        );
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    labels[index([x, y, z])] = 1;
                }
            }
        }
    }
    // The voxels whose centre the surface encloses, row by row along x. The ray is nudged off
    // the grid by an irrational fraction of a voxel so it meets no edge or vertex exactly.
    let nudge = [
        h * 1e-6 * std::f64::consts::SQRT_2,
        h * 1e-6 * std::f64::consts::E,
    ];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            let (py, pz) = (
                origin[1] + y as f64 * h + nudge[0],
                origin[2] + z as f64 * h + nudge[1],
            );
            let mut hits: Vec<f64> = triangles
                .iter()
                .filter_map(|t| crossing(t, py, pz))
                .collect();
            hits.sort_by(f64::total_cmp);
            for pair in hits.chunks_exact(2) {
                for x in 0..dims[0] {
                    let px = origin[0] + x as f64 * h;
                    if px > pair[0] && px < pair[1] {
                        labels[index([x, y, z])] = 1;
                    }
                }
            }
        }
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| "mesh".into());
    Ok(LabelMap {
        dims,
        labels,
        ijk_to_ras: [
            [h, 0.0, 0.0, origin[0]],
            [0.0, h, 0.0, origin[1]],
            [0.0, 0.0, h, origin[2]],
        ],
        named: vec![Segment { name, label: 1 }],
    })
}

/// Where the line {y = py, z = pz} crosses triangle `t` (its x), if it does.
fn crossing(t: &[[f64; 3]; 3], py: f64, pz: f64) -> Option<f64> {
    let [a, b, c] = *t;
    // Barycentric coordinates in the y-z projection.
    let det = (b[1] - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (b[2] - a[2]);
    if det == 0.0 {
        return None;
    }
    let u = ((py - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (pz - a[2])) / det;
    let v = ((b[1] - a[1]) * (pz - a[2]) - (py - a[1]) * (b[2] - a[2])) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]))
}
