//! The instances of Birgin, Lobato and Martínez's Section 6, with the densities they reached:
//! what `ellipack pack --instance NAME` runs and `ellipack instances` lists.
//!
//! * Table 6.1: m ∈ {100, 200, 300, 400, 500, 1000} ellipses with semi-axes (2, 1) in a
//!   minimum-area ellipse — `ellipse-100` … `ellipse-1000`;
//! * Table 6.2: the same in a minimum-area rectangle — `rectangle-100` … `rectangle-1000`;
//! * Table 6.3: m ∈ {100, …, 500} ellipsoids with semi-axes (1, 0.75, 0.5) in a minimum-volume
//!   ball — `ball-100` … `ball-500`;
//! * Table 6.4: the same in a minimum-volume cuboid — `cuboid-100` … `cuboid-500`;
//! * Section 6.1.2: the 231 ellipses with the distinct semi-axes (1 + 0.2α, 1 + 0.2β),
//!   0 ≤ α ≤ β ≤ 20, in a minimum-area circle — `circle-231`. The paper gives the radius it
//!   reached (49.39860), not a density; [`Instance::reference_density`] derives one from it.
//!
//! Areas, volumes and densities are the paper's, rounded to 5 decimals as printed there; each
//! instance was run for 48 hours of CPU time.

use crate::packing::ContainerKind;
use crate::scene::{Dimension, OutputOptions, Scene, ShapeGroup, SolverSettings};
use std::fmt::Write as _;

/// The items of an instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InstanceShapes {
    /// `count` identical items.
    Identical {
        /// How many.
        count: usize,
        /// Their semi-axes (2 or 3 values).
        semi_axes: &'static [f64],
    },
    /// One ellipse for each pair (1 + 0.2α, 1 + 0.2β), 0 ≤ α ≤ β ≤ `steps` (231 ellipses for
    /// 20 steps), in the order α = 0, β = 0..=steps; α = 1, β = 1..=steps; …
    DistinctEllipses {
        /// The largest α and β.
        steps: u32,
    },
}

impl InstanceShapes {
    /// The groups of a scene holding these items (one group per distinct shape).
    pub fn groups(&self) -> Vec<ShapeGroup> {
        match *self {
            InstanceShapes::Identical { count, semi_axes } => {
                vec![ShapeGroup::identical(count, semi_axes.to_vec())]
            }
            InstanceShapes::DistinctEllipses { steps } => {
                // (5 + α) / 5 is the double nearest to 1 + 0.2α; 1.0 + 0.2 * α is not always.
                let length = |k: u32| f64::from(5 + k) / 5.0;
                (0..=steps)
                    .flat_map(|a| {
                        (a..=steps)
                            .map(move |b| ShapeGroup::identical(1, vec![length(a), length(b)]))
                    })
                    .collect()
            }
        }
    }

    /// The number of items.
    pub fn count(&self) -> usize {
        match *self {
            InstanceShapes::Identical { count, .. } => count,
            InstanceShapes::DistinctEllipses { steps } => {
                let n = steps as usize + 1;
                n * (n + 1) / 2
            }
        }
    }

    /// The total area (2D) or volume (3D) of the items.
    pub fn total_measure(&self) -> f64 {
        self.groups()
            .iter()
            .map(|g| {
                let product: f64 = g.semi_axes.iter().product();
                let unit = if g.semi_axes.len() == 2 {
                    std::f64::consts::PI
                } else {
                    4.0 / 3.0 * std::f64::consts::PI
                };
                g.count as f64 * unit * product
            })
            .sum()
    }
}

/// One of the paper's instances and its result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// The name for `--instance`: the container and the item count, e.g. `ball-100`.
    pub name: &'static str,
    /// Where in the paper: "Table 6.1" … "Table 6.4", "Section 6.1.2".
    pub source: &'static str,
    /// The container, whose area or volume is minimised.
    pub container: ContainerKind,
    /// The items.
    pub shapes: InstanceShapes,
    /// The container's area (2D) or volume (3D) in the paper's best solution.
    pub paper_measure: Option<f64>,
    /// The density of the paper's best solution.
    pub paper_density: Option<f64>,
    /// The container's radius in the paper's best solution, where the paper gives it.
    pub paper_radius: Option<f64>,
}

impl Instance {
    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        self.container.dimension()
    }

    /// The number of items.
    pub fn count(&self) -> usize {
        self.shapes.count()
    }

    /// The paper's density, or where it gives only a radius (`circle-231`), the density that
    /// radius implies: total item area / πr².
    pub fn reference_density(&self) -> Option<f64> {
        self.paper_density.or_else(|| {
            let r = self.paper_radius?;
            let measure = match self.container {
                ContainerKind::Circle => std::f64::consts::PI * r * r,
                ContainerKind::Ball => 4.0 / 3.0 * std::f64::consts::PI * r.powi(3),
                _ => return None,
            };
            Some(self.shapes.total_measure() / measure)
        })
    }

    /// E.g. "100 ellipses (2, 1) in a minimum-area ellipse (Table 6.1)".
    pub fn description(&self) -> String {
        let noun = if self.dimension() == 2 {
            "ellipses"
        } else {
            "ellipsoids"
        };
        let shapes = match self.shapes {
            InstanceShapes::Identical { semi_axes, .. } => {
                let list: Vec<String> = semi_axes.iter().map(|l| l.to_string()).collect();
                format!("({})", list.join(", "))
            }
            InstanceShapes::DistinctEllipses { steps } => {
                format!("(1 + 0.2α, 1 + 0.2β), 0 ≤ α ≤ β ≤ {steps},")
            }
        };
        format!(
            "{} {noun} {shapes} in a minimum-{} {} ({})",
            self.count(),
            self.container.measure_name(),
            self.container,
            self.source
        )
    }

    /// The scene that runs this instance: the paper's shapes and container, default solver
    /// settings (ε_feas = ε_opt = 1e-4 as in the paper; the paper's perturbation of 2.5 % in
    /// 2D and 10 % in 3D; the default time limit, far below the paper's 48 hours).
    pub fn scene(&self) -> Scene {
        let dimension = if self.dimension() == 2 {
            Dimension::Two
        } else {
            Dimension::Three
        };
        Scene {
            name: Some(self.description()),
            dimension,
            container: self.container,
            container_size: None,
            shapes: self.shapes.groups(),
            solver: SolverSettings::defaults(dimension),
            seed: 0,
            output: OutputOptions::default(),
        }
    }
}

const ELLIPSE_2_1: &[f64] = &[2.0, 1.0];
const ELLIPSOID_1_075_05: &[f64] = &[1.0, 0.75, 0.5];

const fn row(
    name: &'static str,
    source: &'static str,
    container: ContainerKind,
    semi_axes: &'static [f64],
    count: usize,
    measure: f64,
    density: f64,
) -> Instance {
    Instance {
        name,
        source,
        container,
        shapes: InstanceShapes::Identical { count, semi_axes },
        paper_measure: Some(measure),
        paper_density: Some(density),
        paper_radius: None,
    }
}

use ContainerKind::{Ball, Circle, Cuboid, Ellipse, Rectangle};

/// Every instance of the paper's Section 6, in the paper's order.
// One row per line, as in the paper's tables: easier to check by eye than rustfmt's layout.
#[rustfmt::skip]
pub static INSTANCES: [Instance; 23] = [
    //   name              source       container  shapes              m     area or volume  density
    row("ellipse-100",    "Table 6.1", Ellipse,   ELLIPSE_2_1,        100,  720.94153,  0.87152),
    row("ellipse-200",    "Table 6.1", Ellipse,   ELLIPSE_2_1,        200,  1429.04475, 0.87935),
    row("ellipse-300",    "Table 6.1", Ellipse,   ELLIPSE_2_1,        300,  2135.66113, 0.88261),
    row("ellipse-400",    "Table 6.1", Ellipse,   ELLIPSE_2_1,        400,  2849.03264, 0.88215),
    row("ellipse-500",    "Table 6.1", Ellipse,   ELLIPSE_2_1,        500,  3553.45497, 0.88410),
    row("ellipse-1000",   "Table 6.1", Ellipse,   ELLIPSE_2_1,        1000, 7110.81559, 0.88361),
    row("rectangle-100",  "Table 6.2", Rectangle, ELLIPSE_2_1,        100,  718.30400,  0.87473),
    row("rectangle-200",  "Table 6.2", Rectangle, ELLIPSE_2_1,        200,  1424.01823, 0.88246),
    row("rectangle-300",  "Table 6.2", Rectangle, ELLIPSE_2_1,        300,  2125.50589, 0.88683),
    row("rectangle-400",  "Table 6.2", Rectangle, ELLIPSE_2_1,        400,  2821.35592, 0.89080),
    row("rectangle-500",  "Table 6.2", Rectangle, ELLIPSE_2_1,        500,  3524.99378, 0.89123),
    row("rectangle-1000", "Table 6.2", Rectangle, ELLIPSE_2_1,        1000, 7012.42249, 0.89601),
    Instance {
        name: "circle-231",
        source: "Section 6.1.2",
        container: Circle,
        shapes: InstanceShapes::DistinctEllipses { steps: 20 },
        paper_measure: None,
        paper_density: None,
        paper_radius: Some(49.39860),
    },
    row("ball-100",       "Table 6.3", Ball,      ELLIPSOID_1_075_05, 100,  235.84476,  0.66603),
    row("ball-200",       "Table 6.3", Ball,      ELLIPSOID_1_075_05, 200,  466.02054,  0.67413),
    row("ball-300",       "Table 6.3", Ball,      ELLIPSOID_1_075_05, 300,  690.88831,  0.68208),
    row("ball-400",       "Table 6.3", Ball,      ELLIPSOID_1_075_05, 400,  924.38840,  0.67971),
    row("ball-500",       "Table 6.3", Ball,      ELLIPSOID_1_075_05, 500,  1166.65841, 0.67320),
    row("cuboid-100",     "Table 6.4", Cuboid,    ELLIPSOID_1_075_05, 100,  245.00312,  0.64113),
    row("cuboid-200",     "Table 6.4", Cuboid,    ELLIPSOID_1_075_05, 200,  477.21441,  0.65832),
    row("cuboid-300",     "Table 6.4", Cuboid,    ELLIPSOID_1_075_05, 300,  708.62093,  0.66501),
    row("cuboid-400",     "Table 6.4", Cuboid,    ELLIPSOID_1_075_05, 400,  935.85630,  0.67138),
    row("cuboid-500",     "Table 6.4", Cuboid,    ELLIPSOID_1_075_05, 500,  1163.44519, 0.67506),
];

/// The instance called `name` (exact match), or `None`.
pub fn by_name(name: &str) -> Option<&'static Instance> {
    INSTANCES.iter().find(|i| i.name == name)
}

/// The names of every instance, comma-separated (for "unknown instance" messages).
pub fn names() -> String {
    INSTANCES
        .iter()
        .map(|i| i.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The listing of `ellipack instances`: name, paper's density (`≈` where derived from the
/// radius), container area or volume, description.
pub fn listing() -> String {
    let mut out = format!(
        "{:<15} {:>9} {:>12}  {}\n",
        "name", "density", "area/volume", "instance"
    );
    for i in &INSTANCES {
        let density = match (i.paper_density, i.reference_density()) {
            (Some(d), _) => format!("{d:.5}"),
            (None, Some(d)) => format!("≈{d:.5}"),
            (None, None) => "-".to_string(),
        };
        let measure = match (i.paper_measure, i.paper_radius) {
            (Some(m), _) => format!("{m:.5}"),
            (None, Some(r)) => format!("r = {r:.5}"),
            (None, None) => "-".to_string(),
        };
        // Writing to a String cannot fail.
        let _ = writeln!(
            out,
            "{:<15} {:>9} {:>12}  {}",
            i.name,
            density,
            measure,
            i.description()
        );
    }
    out
}
