//! The receiver grid of a sweep: `x0:x1:dx,y0:y1:dy,z` (metres, world frame), parsed and
//! validated, its size checked against a budget before any point is allocated.

use bt_geom::{Real, Vec3};

/// Default budget on grid points (`--max-points`).
pub const DEFAULT_MAX_POINTS: u64 = 1_000_000;

/// Why a grid is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// The text is not `x0:x1:dx,y0:y1:dy,z`.
    #[error(
        "grid \"{text}\": {message} (expected x0:x1:dx,y0:y1:dy,z in metres, e.g. 0:6:0.5,0:4.5:0.5,1.2)"
    )]
    Syntax {
        /// The grid text as given.
        text: String,
        /// What is wrong, naming the field.
        message: String,
    },
    /// More points than the budget.
    #[error(
        "grid has {} points ({} × {}), more than the budget of {budget}; \
         use a coarser step or raise the budget with --max-points",
        bt_geom::Count(*.points), bt_geom::Count(*.nx), bt_geom::Count(*.ny)
    )]
    TooLarge {
        /// Points the grid would have (saturating).
        points: u64,
        /// Points along x.
        nx: u64,
        /// Points along y.
        ny: u64,
        /// The budget.
        budget: u64,
    },
}

/// One axis of the grid: `start, start + step, …` up to `stop` (inclusive within a
/// millionth of a step), metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    /// First coordinate, metres.
    pub start: Real,
    /// Last coordinate asked for, metres (≥ start).
    pub stop: Real,
    /// Spacing, metres (> 0).
    pub step: Real,
}

impl Axis {
    /// Number of coordinates on the axis (saturating at `u64::MAX`).
    pub fn count(&self) -> u64 {
        // The epsilon keeps 0:1:0.1 at 11 points despite 1/0.1 rounding to 9.999….
        let n = ((self.stop - self.start) / self.step + 1e-6).floor() + 1.0;
        if n >= u64::MAX as Real {
            u64::MAX
        } else {
            n as u64
        }
    }

    /// The `i`-th coordinate (computed, not accumulated, so no drift), metres.
    pub fn at(&self, i: u64) -> Real {
        self.start + i as Real * self.step
    }
}

/// A horizontal grid of receiver points at height `z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Along x.
    pub x: Axis,
    /// Along y.
    pub y: Axis,
    /// Height of every point, metres.
    pub z: Real,
}

impl std::str::FromStr for Grid {
    type Err = GridError;

    /// Parse `x0:x1:dx,y0:y1:dy,z`.
    fn from_str(text: &str) -> Result<Self, GridError> {
        let syntax = |message: String| GridError::Syntax {
            text: text.to_string(),
            message,
        };
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != 3 {
            return Err(syntax(format!(
                "{} comma-separated fields, expected 3",
                fields.len()
            )));
        }
        let x = axis(fields[0], "x").map_err(syntax)?;
        let y = axis(fields[1], "y").map_err(syntax)?;
        let z = number(fields[2], "z").map_err(syntax)?;
        Ok(Grid { x, y, z })
    }
}

fn number(text: &str, name: &str) -> Result<Real, String> {
    let v: Real = text
        .parse()
        .map_err(|_| format!("{name} \"{text}\" is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{name} \"{text}\" is not finite"));
    }
    Ok(v)
}

fn axis(text: &str, name: &str) -> Result<Axis, String> {
    let parts: Vec<&str> = text.split(':').map(str::trim).collect();
    let [start, stop, step] = parts[..] else {
        return Err(format!(
            "{name} axis \"{text}\" has {} colon-separated numbers, expected start:stop:step",
            parts.len()
        ));
    };
    let start = number(start, &format!("{name} start"))?;
    let stop = number(stop, &format!("{name} stop"))?;
    let step = number(step, &format!("{name} step"))?;
    if step <= 0.0 {
        return Err(format!("{name} step must be positive, got {step}"));
    }
    if stop < start {
        return Err(format!("{name} stop {stop} is below its start {start}"));
    }
    Ok(Axis { start, stop, step })
}

impl Grid {
    /// Points along x and y, and their product (all saturating).
    pub fn size(&self) -> (u64, u64, u64) {
        let (nx, ny) = (self.x.count(), self.y.count());
        (nx, ny, nx.saturating_mul(ny))
    }

    /// The points, y rows outer and x inner (the CSV's order), after checking the count
    /// against `budget` (before allocating).
    pub fn points(&self, budget: u64) -> Result<Vec<Vec3>, GridError> {
        let (nx, ny, points) = self.size();
        if points > budget {
            return Err(GridError::TooLarge {
                points,
                nx,
                ny,
                budget,
            });
        }
        let mut out = Vec::with_capacity(points as usize);
        for j in 0..ny {
            for i in 0..nx {
                out.push(Vec3::new(self.x.at(i), self.y.at(j), self.z));
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Grid, GridError> {
        s.parse()
    }

    #[test]
    fn decimal_steps_include_the_stop() {
        let g = parse("0:1:0.1, 0:0.3:0.1, 1.5").unwrap();
        assert_eq!(g.size(), (11, 4, 44));
        let p = g.points(100).unwrap();
        assert_eq!(p[0], Vec3::new(0.0, 0.0, 1.5));
        assert_eq!(p[11], Vec3::new(0.0, 0.1, 1.5));
        assert!((p[43].x - 1.0).abs() < 1e-12 && (p[43].y - 0.3).abs() < 1e-12);
    }

    #[test]
    fn one_point_axes_and_negative_coordinates() {
        let g = parse("-1:-1:0.5,2:2.4:0.5,-0.25").unwrap();
        assert_eq!(g.size(), (1, 1, 1));
        assert_eq!(g.points(1).unwrap(), vec![Vec3::new(-1.0, 2.0, -0.25)]);
    }

    #[test]
    fn bad_syntax_names_the_field() {
        let cases = [
            ("0:1:0.1,0:1:0.1", "2 comma-separated fields"),
            ("0:1,0:1:0.1,1", "x axis \"0:1\" has 2"),
            ("0:1:0.1,0:1:zero,1", "y step \"zero\" is not a number"),
            ("0:1:0,0:1:0.1,1", "x step must be positive"),
            ("0:1:-0.1,0:1:0.1,1", "x step must be positive"),
            ("2:1:0.1,0:1:0.1,1", "x stop 1 is below its start 2"),
            ("0:1:0.1,0:1:0.1,nan", "z \"nan\" is not finite"),
            ("0:inf:0.1,0:1:0.1,1", "x stop \"inf\" is not finite"),
        ];
        for (text, expected) in cases {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(expected), "{text}: {e}");
            assert!(e.contains("x0:x1:dx,y0:y1:dy,z"), "{text}: {e}");
        }
    }

    #[test]
    fn too_large_is_refused_before_allocating() {
        // 1e12 × 1e12 points would not fit in memory: the budget check comes first.
        let g = parse("0:1e6:1e-6,0:1e6:1e-6,1").unwrap();
        let e = g.points(DEFAULT_MAX_POINTS).unwrap_err();
        assert!(matches!(e, GridError::TooLarge { .. }));
        assert!(e.to_string().contains("--max-points"), "{e}");
        let g = parse("0:9:1,0:9:1,1").unwrap();
        assert_eq!(g.points(100).unwrap().len(), 100);
        assert!(g.points(99).is_err());
    }
}
