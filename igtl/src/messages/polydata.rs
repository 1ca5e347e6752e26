//! POLYDATA (`Documents/Protocol/polydata.md`), the part a needle path needs: points and one
//! LINES polyline.
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
//! attributes, which come last.

use crate::bytes::{Reader, Writer};
use crate::Error;
use heapless::Vec;

/// Bytes of the POLYDATA header.
pub const POLYDATA_HEADER_SIZE: usize = 40;
/// Points (and line indices) kept per message.
pub const MAX_POLY_POINTS: usize = 256;

/// Points and at most one polyline through them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PolyData {
    points: Vec<[f32; 3], MAX_POLY_POINTS>,
    line: Vec<u32, MAX_POLY_POINTS>,
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
        })
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

    /// Writes the body: header, points, and the polyline as the one LINES cell.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        // The bounds keep every count and size far below u32::MAX.
        let npoints = self.points.len() as u32;
        let (nlines, size_lines) = if self.line.is_empty() {
            (0, 0)
        } else {
            (1, 4 * (self.line.len() as u32 + 1))
        };
        let mut w = Writer::new(out);
        for v in [npoints, 0, 0, nlines, size_lines, 0, 0, 0, 0, 0] {
            w.u32(v)?;
        }
        for p in &self.points {
            w.f32s(p)?;
        }
        if nlines == 1 {
            w.u32(self.line.len() as u32)?;
            self.line.iter().try_for_each(|&i| w.u32(i))?;
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
        Ok(PolyData { points, line })
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
