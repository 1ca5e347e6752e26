//! POLYDATA (`Documents/Protocol/polydata.md`), the part a needle path and a mesh need: points,
//! one LINES polyline, and (sent only) triangles as POLYGONS cells.
//!
//! ```text
//! header  10 × u32: npoints, nvertices, size_vertices, nlines, size_lines, npolygons,
//!         size_polygons, ntriangle_strips, size_triangle_strips, nattributes
//! points  npoints × (x, y, z) f32
//! cells   vertices, lines, polygons, triangle strips, each size_* bytes of
//!         u32 (n, index_0 … index_n-1) per cell
//! then    attribute headers, names and data
//! ```
//!
//! The size_* fields are in bytes (the document says "total size"; the reference library
//! allocates and advances by them as bytes and rejects any that is not a multiple of 4).
//! Vertex, polygon and triangle strip cells received are skipped by their size, and so are
//! attributes, which come last: a mesh is sent (the obstacles to Slicer), never read back, so
//! a decoded POLYDATA has no triangles.

use crate::bytes::{Reader, Writer};
use crate::Error;
use heapless::Vec;

/// Bytes of the POLYDATA header.
pub const POLYDATA_HEADER_SIZE: usize = 40;
/// Points (and line indices) kept per message.
pub const MAX_POLY_POINTS: usize = 256;
/// Triangles kept per message (twice the points: a closed mesh has about that many).
pub const MAX_POLY_TRIANGLES: usize = 2 * MAX_POLY_POINTS;

// A triangle's indices are kept in a byte each (1.5 KiB for all, not 6): they must fit.
const _: () = assert!(MAX_POLY_POINTS <= 256);

/// Points, at most one polyline through them, and triangles on them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PolyData {
    points: Vec<[f32; 3], MAX_POLY_POINTS>,
    line: Vec<u32, MAX_POLY_POINTS>,
    /// Indices into `points`, a byte each (see [`MAX_POLY_POINTS`]).
    triangles: Vec<[u8; 3], MAX_POLY_TRIANGLES>,
}

/// Counts and sizes of the POLYDATA header, as sent.
struct Counts {
    npoints: u32,
    size_vertices: u32,
    nlines: u32,
    size_lines: u32,
    size_polygons: u32,
    size_strips: u32,
    nattributes: u32,
}

impl PolyData {
    /// Points (mm) and a polyline given by indices into them (empty for none): `TooLarge` past
    /// [`MAX_POLY_POINTS`], `NotFinite` for a NaN or infinite coordinate, `Malformed` for an
    /// index past the points.
    pub fn new(points: &[[f32; 3]], line: &[u32]) -> Result<Self, Error> {
        if points.iter().flatten().any(|c| !c.is_finite()) {
            return Err(Error::NotFinite);
        }
        if line
            .iter()
            .any(|&i| usize::try_from(i).map_or(true, |i| i >= points.len()))
        {
            return Err(Error::Malformed);
        }
        Ok(PolyData {
            points: Vec::from_slice(points).map_err(|_| Error::TooLarge)?,
            line: Vec::from_slice(line).map_err(|_| Error::TooLarge)?,
            triangles: Vec::new(),
        })
    }

    /// A mesh: points (mm) and triangles given by indices into them, each one POLYGONS cell of
    /// three (`TooLarge` past [`MAX_POLY_POINTS`] or [`MAX_POLY_TRIANGLES`], `NotFinite`,
    /// `Malformed` for an index past the points). Sent only: a decoded one has no triangles.
    pub fn mesh(points: &[[f32; 3]], triangles: &[[u32; 3]]) -> Result<Self, Error> {
        let mut mesh = PolyData::new(points, &[])?;
        for t in triangles {
            let mut small = [0u8; 3];
            for (s, &i) in small.iter_mut().zip(t) {
                // Below the points' count, so below 256: a byte holds it.
                *s = u8::try_from(i)
                    .ok()
                    .filter(|&b| usize::from(b) < points.len())
                    .ok_or(Error::Malformed)?;
            }
            mesh.triangles.push(small).map_err(|_| Error::TooLarge)?;
        }
        Ok(mesh)
    }

    /// The points joined in order by one polyline (a path).
    pub fn polyline(points: &[[f32; 3]]) -> Result<Self, Error> {
        if points.len() > MAX_POLY_POINTS {
            return Err(Error::TooLarge);
        }
        let mut line: Vec<u32, MAX_POLY_POINTS> = Vec::new();
        for i in 0..points.len() as u32 {
            line.push(i).map_err(|_| Error::TooLarge)?;
        }
        PolyData::new(points, &line)
    }

    /// The points in mm.
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// The polyline's point indices (empty if there is none).
    pub fn line(&self) -> &[u32] {
        &self.line
    }

    /// The triangles' point indices (none on every decoded one).
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.triangles.iter().map(|t| t.map(u32::from))
    }

    /// Writes the body: header, points, the polyline as the one LINES cell, and each triangle
    /// as a POLYGONS cell of three.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        // The bounds keep every count and size far below u32::MAX.
        let npoints = self.points.len() as u32;
        let (nlines, size_lines) = if self.line.is_empty() {
            (0, 0)
        } else {
            (1, 4 * (self.line.len() as u32 + 1))
        };
        let npolygons = self.triangles.len() as u32;
        let size_polygons = 16 * npolygons;
        let mut w = Writer::new(out);
        for v in [
            npoints,
            0,
            0,
            nlines,
            size_lines,
            npolygons,
            size_polygons,
            0,
            0,
            0,
        ] {
            w.u32(v)?;
        }
        for p in &self.points {
            w.f32s(p)?;
        }
        if nlines == 1 {
            w.u32(self.line.len() as u32)?;
            self.line.iter().try_for_each(|&i| w.u32(i))?;
        }
        for t in &self.triangles {
            w.u32(3)?;
            t.iter().try_for_each(|&i| w.u32(u32::from(i)))?;
        }
        Ok(w.len())
    }

    /// Reads a body: `BadBodySize` if it is shorter than its counts say (or longer, without
    /// attributes), `TooLarge` past [`MAX_POLY_POINTS`], `Unsupported` for more than one line,
    /// `Malformed` for cell sizes that contradict their contents.
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        let mut r = Reader::new(content);
        let c = Counts::read(&mut r)?;
        c.check_size(content.len())?;
        if c.npoints as usize > MAX_POLY_POINTS {
            return Err(Error::TooLarge);
        }
        let mut points = Vec::new();
        for _ in 0..c.npoints {
            points.push(r.finite3()?).map_err(|_| Error::TooLarge)?;
        }
        r.take(c.size_vertices as usize)?;
        let line = read_line(r.take(c.size_lines as usize)?, c.nlines, c.npoints)?;
        // Polygons, strips and attributes are skipped: check_size already bounded them.
        Ok(PolyData {
            points,
            line,
            triangles: Vec::new(),
        })
    }
}

impl Counts {
    fn read(r: &mut Reader<'_>) -> Result<Self, Error> {
        let mut f = [0u32; 10];
        for v in &mut f {
            *v = r.u32().map_err(|_| Error::BadBodySize)?;
        }
        let c = Counts {
            npoints: f[0],
            size_vertices: f[2],
            nlines: f[3],
            size_lines: f[4],
            size_polygons: f[6],
            size_strips: f[8],
            nattributes: f[9],
        };
        let sizes = [
            c.size_vertices,
            c.size_lines,
            c.size_polygons,
            c.size_strips,
        ];
        if sizes.iter().any(|s| s % 4 != 0) {
            return Err(Error::Malformed);
        }
        Ok(c)
    }

    /// The body must hold header, points and cells; exactly, unless attributes follow.
    fn check_size(&self, len: usize) -> Result<(), Error> {
        // u64: four u32 sizes and 12 × u32 points cannot overflow it.
        let needed = POLYDATA_HEADER_SIZE as u64
            + 12 * u64::from(self.npoints)
            + u64::from(self.size_vertices)
            + u64::from(self.size_lines)
            + u64::from(self.size_polygons)
            + u64::from(self.size_strips);
        let len = len as u64;
        let fits = if self.nattributes == 0 {
            len == needed
        } else {
            len >= needed
        };
        if fits {
            Ok(())
        } else {
            Err(Error::BadBodySize)
        }
    }
}

/// The one polyline of the LINES array, which must be exactly its cell.
fn read_line(cells: &[u8], nlines: u32, npoints: u32) -> Result<Vec<u32, MAX_POLY_POINTS>, Error> {
    let mut line = Vec::new();
    match nlines {
        0 if cells.is_empty() => return Ok(line),
        0 => return Err(Error::Malformed),
        1 => {}
        _ => return Err(Error::Unsupported),
    }
    let mut r = Reader::new(cells);
    let n = r.u32()?;
    if u64::from(n) * 4 != r.remaining() as u64 {
        return Err(Error::Malformed);
    }
    for _ in 0..n {
        let i = r.u32()?;
        if i >= npoints {
            return Err(Error::Malformed);
        }
        line.push(i).map_err(|_| Error::TooLarge)?;
    }
    Ok(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    /// A tetrahedron: counts and sizes in the header, each triangle a cell of three after the
    /// points; read back, the points stay and the polygons are skipped by their size.
    #[test]
    fn a_mesh_is_sent_as_polygon_cells_of_three() {
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mesh = PolyData::mesh(&points, &triangles).unwrap();
        assert!(mesh.triangles().eq(triangles));
        let mut out = [0u8; 512];
        let n = mesh.encode(&mut out).unwrap();
        assert_eq!(n, POLYDATA_HEADER_SIZE + 4 * 12 + 4 * 16);
        let header: [u32; 10] = core::array::from_fn(|i| u32_at(&out, 4 * i));
        assert_eq!(header, [4, 0, 0, 0, 0, 4, 64, 0, 0, 0]);
        let cells = POLYDATA_HEADER_SIZE + 4 * 12;
        assert_eq!(
            [0, 1, 2, 3].map(|k| u32_at(&out, cells + 16 + 4 * k)),
            [3, 0, 1, 3]
        );
        let back = PolyData::decode(&out[..n]).unwrap();
        assert_eq!(back.points(), points);
        assert_eq!(back.triangles().count(), 0);
        assert_eq!(
            PolyData::mesh(&points, &[[0, 1, 4]]),
            Err(Error::Malformed),
            "an index past the points"
        );
        let too_many = [[0, 1, 2]; MAX_POLY_TRIANGLES + 1];
        assert_eq!(PolyData::mesh(&points, &too_many), Err(Error::TooLarge));
    }
}
