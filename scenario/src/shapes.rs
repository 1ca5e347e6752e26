//! A scenario file's obstacles as the planner sees them: circles kept as written, polygons
//! checked and covered by circles (see [`super::approx`]).

use super::approx::{approximate, Approximation, Method};
use super::file::{ObstacleFile, ScenarioFile};
use super::polygon::Polygon;
use anyhow::{bail, Context, Result};
use planner_core::model::scenario::Obstacle;

/// One `[[obstacles]]` or `[[anatomy]]` entry as the planner sees it: its circles, and the
/// polygon they replace.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleShape {
    /// Index in the file's `[[obstacles]]` list; `[[anatomy]]` entries count on after them.
    pub index: usize,
    /// The polygon and its covering circles, for polygon obstacles.
    pub polygon: Option<(Polygon, Approximation)>,
    /// Circles (spheres) handed to the planner.
    pub circles: Vec<Obstacle>,
}

impl ScenarioFile {
    /// The obstacles as circles; polygons are approximated by `approx` when given, else by
    /// their own `approx` key (default segmented). Radii are rounded up by 0.001 mm so the
    /// planner's `f32` circles still cover the polygon.
    pub fn obstacle_shapes(&self, approx: Option<Method>) -> Result<Vec<ObstacleShape>> {
        let plane = self
            .planner
            .as_ref()
            .and_then(|p| p.plane.as_deref())
            .is_some_and(|s| s.eq_ignore_ascii_case("yz"));
        let x = self.entry_position()?[0];
        let mut shapes = Vec::with_capacity(self.obstacles.len());
        for (index, o) in self.obstacles.iter().enumerate() {
            let shape = self
                .obstacle_shape(index, o, approx, plane, x)
                .with_context(|| format!("in obstacles[{index}]"))?;
            shapes.push(shape);
        }
        let used = shapes.iter().map(|s| s.circles.len()).sum();
        shapes.extend(self.anatomy_shapes(plane, used)?);
        Ok(shapes)
    }

    fn obstacle_shape(
        &self,
        index: usize,
        o: &ObstacleFile,
        approx: Option<Method>,
        plane: bool,
        x: f32,
    ) -> Result<ObstacleShape> {
        let outline = match (&o.polygon, &o.polygon_file) {
            (Some(_), Some(_)) => bail!("give either polygon or polygon_file, not both"),
            (Some(v), None) => Some(Polygon::new(v.clone())?),
            (None, Some(f)) => {
                let path = self
                    .base_dir
                    .as_deref()
                    .map(|d| d.join(f))
                    .unwrap_or_else(|| f.clone());
                let text = std::fs::read_to_string(&path)
                    .with_context(|| format!("cannot read polygon file {}", path.display()))?;
                Some(
                    Polygon::parse_text(&text)
                        .with_context(|| format!("in polygon file {}", path.display()))?,
                )
            }
            (None, None) => None,
        };
        let Some(poly) = outline else {
            if o.approx.is_some() {
                bail!("approx applies to polygon obstacles only");
            }
            let (Some(center), Some(radius)) = (o.center, o.radius) else {
                bail!("give center and radius, or a polygon (polygon = [[y, z], ...] or polygon_file)");
            };
            return Ok(ObstacleShape {
                index,
                polygon: None,
                circles: vec![Obstacle { center, radius }],
            });
        };
        if o.center.is_some() || o.radius.is_some() {
            bail!("a polygon obstacle takes no center or radius");
        }
        if !plane {
            bail!("polygon obstacles lie in the y-z plane: they need planner.plane = \"yz\"");
        }
        let method = match (approx, o.approx.as_deref()) {
            (Some(m), _) => m,
            (None, Some(name)) => name.parse()?,
            (None, None) => Method::default(),
        };
        let approximation = approximate(&poly, method);
        let inside_msg = |what: &str, p: [f32; 3]| -> Result<()> {
            let q = [f64::from(p[1]), f64::from(p[2])];
            if poly.contains(q) {
                bail!("the {what} lies inside the polygon");
            }
            if approximation.circles.iter().any(|c| c.contains(q, 1e-3)) {
                bail!(
                    "the {what} lies outside the polygon but inside its {method} circles: \
                     try a tighter approximation (approx = \"bordered\" or \"segmented\")"
                );
            }
            Ok(())
        };
        inside_msg("entry point", self.entry_position()?)?;
        inside_msg("target", self.target_position()?)?;
        let circles = approximation
            .circles
            .iter()
            .map(|c| Obstacle {
                center: [x, c.center[0] as f32, c.center[1] as f32],
                radius: (c.radius + 1e-3) as f32,
            })
            .collect();
        Ok(ObstacleShape {
            index,
            polygon: Some((poly, approximation)),
            circles,
        })
    }
}
