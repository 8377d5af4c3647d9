//! Operation method knowledge (thesis §4.3, §5.3.3, §6.3.3, table 6.1),
//! read from `knowledge/methods.ron`.
//!
//! A method says how one machining feature is milled, chosen by the
//! feature's adjacency: whether its bottom is product and on how many of its
//! side edges it touches product (none: open, some: partially open, all:
//! closed). It fixes the pattern, the tool rule, stepover and depth of cut per
//! region (boundary / full cut / rest), mirrored alternating z-levels, the
//! full-cut criterion, a separate product-adjacent bottom layer, the entry
//! and the run-up to boundary passes. `thinplan-operations` applies it; every
//! operation carries `methods.<method id>` as its provenance rule. This
//! module is only the data and the checks on it.

use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range, Seg};

/// The name of the methods file at the knowledge root.
pub const METHODS_FILE: &str = "methods.ron";

/// All operation methods plus the settings every method shares.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodKnowledge {
    /// Spindle direction: with `Clockwise` (M3) down milling keeps the
    /// material on the right of the tool's travel (cutter compensation G41).
    pub spindle: SpindleDirection,
    /// Links run this far (mm) above the top of the feature being cut.
    pub safe_clearance: f64,
    /// Feed moves that are not cutting (descending into a cleared level, a
    /// lead-out) run at this fraction of the roughing feed.
    pub link_feed_factor: f64,
    /// A path junction turning more than this (degrees) is a corner where the
    /// time model brings the feed to zero.
    pub corner_angle_deg: f64,
    /// Where a run-up, a run-off or an entry helix does not fit, it is
    /// tried again at these fractions of its size, largest first (then a
    /// straight lead-in, or a ramp).
    pub fit_scales: Vec<f64>,
    /// The quarter circle that leads a boundary pass off into cleared
    /// space, radius a fraction of D.
    pub run_off_radius: f64,
    /// How high links that leave cleared space run (stage 8).
    pub links: LinkHeight,
    /// How passes meet product faces that slope (absent: `Follow`).
    #[serde(default)]
    pub sloped_faces: SlopedFaces,
    /// Through features (nothing below their open bottom but the blank's
    /// underside): their bottom level goes this far (mm) below the blank,
    /// plus the tool's corner radius, so the corner leaves no ring at the
    /// foot of the opening.
    pub breakthrough: f64,
    /// A tool may cut down to `stickout − holder_clearance` (mm) below the
    /// top of the stock, never deeper: its holder's face stays this far
    /// above the highest stock it could meet (tool reach).
    pub holder_clearance: f64,
    /// The methods, tried in order: the first whose `applies` matches a
    /// feature is used.
    pub methods: Vec<Method>,
}

/// The height of links that leave cleared space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LinkHeight {
    /// Over the top of the whole stock plus `safe_clearance`.
    OverTheTop,
    /// At the lowest height the in-process stock allows: `safe_clearance`
    /// above the highest stock under the tool, its shank and its holder
    /// along the link, as the operations before it leave it.
    InProcessStock,
}

/// How passes meet a product face that slopes within a slab (a chamfer, a
/// cut-out's round bottom).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SlopedFaces {
    /// The tool's profile (its corner radius) touches the face: the product
    /// edge moves to where it does, for the tool and the slab's bottom
    /// (stage 6 samples the face, `MachiningFeature::slopes`).
    #[default]
    Follow,
    /// The face is taken as vertical at the slab's middle section: the
    /// corner radius stands off it and material stays on it.
    AsVertical,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SpindleDirection {
    /// M3.
    Clockwise,
    /// M4.
    CounterClockwise,
}

/// One operation method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    pub id: String,
    pub applies: Applies,
    /// The pattern of the rest region.
    pub pattern: Pattern,
    pub tool: ToolRule,
    /// The boundary region along product edges (reduced stepover, down
    /// milling, run-up); `None`: no boundary passes (only sensible when the
    /// method applies to features without product sides).
    pub boundary: Option<BoundaryRegion>,
    /// The rest region: roughing conditions.
    pub rest: RestRegion,
    pub full_cut: FullCut,
    pub mirror_layers: MirrorLayers,
    /// A separate layer at a product floor with finishing conditions.
    pub bottom_layer: Option<BottomLayer>,
    /// A rest pass at a product floor: where the feature's tool leaves a
    /// fillet at the foot of product walls (its corner radius), a smaller
    /// corner radius of the tool set finishes it; `None`: no rest pass.
    #[serde(default)]
    pub rest_pass: Option<RestPass>,
    /// A rest pass up the product walls: where the feature's tool cannot
    /// come beside a wall (corners and fillets at its ends narrower than
    /// the tool) and leaves more than `min_left` on it, a smaller tool of
    /// the set finishes those stretches at every level; `None`: no pass.
    #[serde(default)]
    pub wall_rest: Option<WallRest>,
    pub entry: LevelEntry,
    /// How far the tool may reach beyond non-product edges.
    pub overhang: Overhang,
    /// Radius (fraction of D) with which the sharp turns of the rest pattern
    /// are rounded.
    pub corner_rounding: f64,
    #[serde(default)]
    pub note: String,
}

/// Which features a method is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Applies {
    pub bottom: BottomMatch,
    pub sides: SidesMatch,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum BottomMatch {
    /// The bottom is product (a floor to finish).
    Product,
    /// The bottom is open or another feature.
    NotProduct,
    Any,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum SidesMatch {
    /// No side edge is product.
    Open,
    /// Some, not all, side edges are product.
    PartiallyOpen,
    /// Every side edge is product (a pocket); no open side to enter from.
    Closed,
    Any,
}

impl BottomMatch {
    pub fn matches(self, bottom_is_product: bool) -> bool {
        match self {
            BottomMatch::Product => bottom_is_product,
            BottomMatch::NotProduct => !bottom_is_product,
            BottomMatch::Any => true,
        }
    }
}

impl SidesMatch {
    pub fn matches(self, sides: SidesMatch) -> bool {
        self == SidesMatch::Any || self == sides
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pattern {
    /// Parallel side passes, alternating direction.
    ZigZag,
    /// Parallel side passes, all in one direction, returning at safe height.
    OneWay,
    /// Parallel offsets of the pocket (closed profiles).
    OffsetSpiral,
    /// Bieterman & Sandstrom's curvilinear spiral (closed profiles; falls
    /// back to offsets where it cannot be built).
    CurvilinearSpiral,
}

impl Pattern {
    pub fn is_spiral(self) -> bool {
        matches!(self, Pattern::OffsetSpiral | Pattern::CurvilinearSpiral)
    }
}

/// Which tool of the set-up's tool set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolRule {
    /// The largest tool whose tool-centre region is not empty (it fits).
    pub choice: ToolChoice,
    /// When the feature has concave product corners of radius ρ, only tools
    /// with radius ≤ `corner_ratio`·ρ are used (§6.3.3: a tool smaller than
    /// the smallest corner, so the boundary pass has no sharp corners).
    /// `None`: corners are not considered.
    pub corner_ratio: Option<f64>,
    /// The tool kinds the method may use (absent: flat and bull-nose end
    /// mills; a ball end mill leaves scallops on the flat floors and the
    /// walls' feet these methods cut).
    #[serde(default = "level_cutters")]
    pub kinds: Vec<crate::ToolKind>,
}

fn level_cutters() -> Vec<crate::ToolKind> {
    vec![
        crate::ToolKind::FlatEndMill,
        crate::ToolKind::BullNoseEndMill,
    ]
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ToolChoice {
    LargestThatFits,
    SmallestThatFits,
}

/// The boundary region: passes along product edges at exactly the tool
/// radius from them, down milling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundaryRegion {
    /// Width of cut of the boundary pass (fraction of D); the rest region
    /// stops this far from it.
    pub stepover: f64,
    /// Largest depth of cut of a boundary pass (fraction of D); a z-level
    /// deeper than this gets stacked boundary passes.
    pub depth: f64,
    pub run_up: RunUp,
    /// Finishing cutting conditions (feed per tooth) on the boundary passes.
    pub finishing: bool,
}

/// The run-up to a boundary pass (figure 4.17).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum RunUp {
    /// A straight lead-in along the pass's tangent, `length` a fraction of D.
    Tangential { length: f64 },
    /// A quarter circle from the cleared side, `radius` a fraction of D.
    Circular { radius: f64 },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestRegion {
    /// Largest stepover (fraction of D); the passes are spread evenly.
    pub stepover: f64,
    /// Largest depth of cut (fraction of D, also capped by the flute length).
    pub depth: f64,
}

/// When z-levels get a full-cut (slot) pass, with reduced depth (§4.3.4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum FullCut {
    Never,
    /// Every z-level starts with a full cut (closed profiles and slots):
    /// its depth is the rest depth times `depth_factor`.
    Always {
        depth_factor: f64,
    },
    /// §6.3.3: with product sides and an odd number of side passes,
    /// alternating layers need a full cut in every second layer; applied only
    /// when that gives fewer side passes in total than the alternative.
    WhenFewerSidePasses {
        depth_factor: f64,
    },
}

/// Mirrored alternating z-levels (figure 4.22).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MirrorLayers {
    Never,
    /// When a z-level ends away from where it started (an odd number of
    /// side passes), the next one runs it backwards.
    WhenOddPasses,
    Always,
}

/// A separate layer at a product floor (§6.3.1: its own operation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BottomLayer {
    /// Thickness of the layer (mm) left above the floor by the other layers.
    pub thickness: f64,
    /// Stepover of its passes (fraction of D).
    pub stepover: f64,
    /// Its pattern: one-way keeps every pass down milling.
    pub pattern: Pattern,
}

/// The rest (corner) pass along the foot of product walls on a product
/// floor, with the tool of the set that has the smallest corner radius
/// (then the largest diameter), when it is smaller than the feature tool's
/// by at least `min_corner_gain`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestPass {
    /// Least corner-radius difference (mm) worth a pass: the fillet left
    /// grows with the square of the difference.
    pub min_corner_gain: f64,
    /// Run-up onto each pass (from the floor the feature's tool cleared).
    pub run_up: RunUp,
}

/// The rest pass up product walls, with the largest tool of the set that
/// is smaller than the feature's tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallRest {
    /// Least thickness (mm) left on the wall by the feature's tool worth a
    /// pass.
    pub min_left: f64,
    /// Run-up onto each pass (from the space the feature's tool cleared).
    pub run_up: RunUp,
    /// `true`: stage 8 runs these passes at the end with the floor rest
    /// passes, one tool change for all; `false`: right after the feature's
    /// other operations, while what stands beside the wall still supports
    /// it (a tool change there and back for every feature).
    pub run_last: bool,
}

/// How the tool gets down to a z-level: never an axial plunge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum LevelEntry {
    /// Ramping along the first pass (back and forth where it is short).
    Ramp { angle_deg: f64 },
    /// A helix of `radius` (fraction of D) where it fits, otherwise a ramp
    /// at the same angle.
    Helix { angle_deg: f64, radius: f64 },
}

impl LevelEntry {
    pub fn angle_deg(self) -> f64 {
        match self {
            LevelEntry::Ramp { angle_deg } | LevelEntry::Helix { angle_deg, .. } => angle_deg,
        }
    }
}

/// How far (fraction of D) the tool's cutting edge may pass beyond an edge
/// that is not product (product edges: never, 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overhang {
    /// Beyond open edges (air or already removed).
    pub open: f64,
    /// Into a neighbouring machining feature not yet removed (at most ½).
    pub feature: f64,
}

impl MethodKnowledge {
    /// The first method that applies to a feature.
    pub fn for_feature(&self, bottom_is_product: bool, sides: SidesMatch) -> Option<&Method> {
        self.methods
            .iter()
            .find(|m| m.applies.bottom.matches(bottom_is_product) && m.applies.sides.matches(sides))
    }

    /// Problems a parser cannot find: duplicate ids, combinations no method
    /// covers, numbers out of range, patterns that cannot serve the sides.
    pub fn problems(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `methods.ron`. Stepovers and
    /// depths are fractions of the tool diameter D (≥ 0.2 mm, `tools/`): at
    /// least 0.01 · D keeps a 1 m feature under 5·10⁵ passes or levels.
    pub fn checks(&self, c: &mut Checks) {
        c.range(
            at!["breakthrough"],
            "",
            "breakthrough",
            self.breakthrough,
            Range::closed(0.0, 10.0),
            " mm",
        );
        c.range(
            at!["holder_clearance"],
            "",
            "holder_clearance",
            self.holder_clearance,
            Range::closed(0.0, 100.0),
            " mm",
        );
        c.range(
            at!["safe_clearance"],
            "",
            "safe_clearance",
            self.safe_clearance,
            Range::above(0.0, 1000.0),
            " mm",
        );
        // Links run at this fraction of the roughing feed: bounded below so
        // they never round to F0.
        c.range(
            at!["link_feed_factor"],
            "",
            "link_feed_factor",
            self.link_feed_factor,
            Range::closed(0.01, 10.0),
            " (fraction of the roughing feed)",
        );
        c.range(
            at!["corner_angle_deg"],
            "",
            "corner_angle_deg",
            self.corner_angle_deg,
            Range::closed(0.0, 180.0),
            "°",
        );
        let descending = self.fit_scales.windows(2).all(|w| w[0] > w[1]);
        if self.fit_scales.is_empty()
            || !descending
            || self
                .fit_scales
                .iter()
                .any(|s| !(s.is_finite() && *s > 0.0 && *s <= 1.0))
        {
            c.push(
                at!["fit_scales"],
                format!(
                    "fit_scales {:?} must be one or more fractions in (0, 1], largest first",
                    self.fit_scales
                ),
            );
        }
        c.range(
            at!["run_off_radius"],
            "",
            "run_off_radius",
            self.run_off_radius,
            Range::above(0.0, 10.0),
            "",
        );
        let mut ids = BTreeSet::new();
        for (i, m) in self.methods.iter().enumerate() {
            let here = |f: &'static str| at!["methods", i, f];
            let id = if m.id.is_empty() {
                c.push(here("id"), format!("method #{} has an empty id", i + 1));
                format!("#{}", i + 1)
            } else {
                m.id.clone()
            };
            if !m.id.is_empty() && !ids.insert(m.id.as_str()) {
                c.push(here("id"), format!("method `{id}`: duplicate id"));
            }
            let p = format!("method `{id}`: ");
            let stepover = Range::closed(0.01, 1.0);
            let depth = Range::closed(0.01, 10.0);
            let of_d = " (fraction of D)";
            c.range(
                at!["methods", i, "rest", "stepover"],
                &p,
                "rest.stepover",
                m.rest.stepover,
                stepover,
                of_d,
            );
            c.range(
                at!["methods", i, "rest", "depth"],
                &p,
                "rest.depth",
                m.rest.depth,
                depth,
                of_d,
            );
            if let Some(b) = &m.boundary {
                c.range(
                    at!["methods", i, "boundary", "stepover"],
                    &p,
                    "boundary.stepover",
                    b.stepover,
                    Range::closed(0.01, 0.5),
                    of_d,
                );
                c.range(
                    at!["methods", i, "boundary", "depth"],
                    &p,
                    "boundary.depth",
                    b.depth,
                    depth,
                    of_d,
                );
                run_up(c, at!["methods", i, "boundary", "run_up"], &p, b.run_up);
            } else if matches!(
                m.applies.sides,
                SidesMatch::PartiallyOpen | SidesMatch::Closed | SidesMatch::Any
            ) {
                c.push(
                    here("boundary"),
                    format!(
                        "method `{id}`: applies to features with product sides but has no \
                         boundary region (product edges would be finished with roughing \
                         conditions)"
                    ),
                );
            }
            match m.full_cut {
                FullCut::Never => {}
                FullCut::Always { depth_factor }
                | FullCut::WhenFewerSidePasses { depth_factor } => c.range(
                    at!["methods", i, "full_cut", "depth_factor"],
                    &p,
                    "full_cut depth_factor",
                    depth_factor,
                    Range::closed(0.01, 1.0),
                    " (fraction of the rest depth)",
                ),
            }
            if let Some(b) = &m.bottom_layer {
                c.range(
                    at!["methods", i, "bottom_layer", "thickness"],
                    &p,
                    "bottom_layer thickness",
                    b.thickness,
                    Range::closed(0.01, 100.0),
                    " mm",
                );
                c.range(
                    at!["methods", i, "bottom_layer", "stepover"],
                    &p,
                    "bottom_layer stepover",
                    b.stepover,
                    stepover,
                    of_d,
                );
                if b.pattern.is_spiral() != m.pattern.is_spiral() {
                    c.push(
                        at!["methods", i, "bottom_layer", "pattern"],
                        format!(
                            "method `{id}`: bottom_layer pattern {:?} must be of the same family \
                             (spiral or parallel passes) as the method's {:?}",
                            b.pattern, m.pattern
                        ),
                    );
                }
            } else if m.applies.bottom == BottomMatch::Product {
                c.push(
                    here("bottom_layer"),
                    format!("method `{id}`: applies to product floors but has no bottom_layer"),
                );
            }
            if let Some(r) = &m.rest_pass {
                c.range(
                    at!["methods", i, "rest_pass", "min_corner_gain"],
                    &p,
                    "rest_pass min_corner_gain",
                    r.min_corner_gain,
                    Range::above(0.0, 100.0),
                    " mm",
                );
                run_up(c, at!["methods", i, "rest_pass", "run_up"], &p, r.run_up);
                if m.applies.bottom == BottomMatch::NotProduct {
                    c.push(
                        here("rest_pass"),
                        format!(
                            "method `{id}`: a rest_pass finishes product floors, but the method \
                             applies to features without one"
                        ),
                    );
                }
            }
            if let Some(w) = &m.wall_rest {
                c.range(
                    at!["methods", i, "wall_rest", "min_left"],
                    &p,
                    "wall_rest min_left",
                    w.min_left,
                    Range::above(0.0, 100.0),
                    " mm",
                );
                run_up(c, at!["methods", i, "wall_rest", "run_up"], &p, w.run_up);
                if m.boundary.is_none() {
                    c.push(
                        here("wall_rest"),
                        format!(
                            "method `{id}`: a wall_rest finishes product walls, but the method \
                             has no boundary region (no product sides)"
                        ),
                    );
                }
            }
            // A ramp is depth / tan(angle) long: 0.5° keeps it under 115 · depth.
            let a = m.entry.angle_deg();
            if !Range::closed(0.5, 45.0).contains(a) {
                c.push(
                    at!["methods", i, "entry", "angle_deg"],
                    format!("method `{id}`: entry angle {a}° must lie in [0.5, 45] (no plunges)"),
                );
            }
            if let LevelEntry::Helix { radius, .. } = m.entry {
                c.range(
                    at!["methods", i, "entry", "radius"],
                    &p,
                    "helix radius",
                    radius,
                    Range::above(0.0, 5.0),
                    of_d,
                );
            }
            c.range(
                at!["methods", i, "overhang", "open"],
                &p,
                "overhang.open",
                m.overhang.open,
                Range::closed(0.0, 10.0),
                of_d,
            );
            c.range(
                at!["methods", i, "overhang", "feature"],
                &p,
                "overhang.feature",
                m.overhang.feature,
                Range::closed(0.0, 0.5),
                " (never more than half the tool into a neighbouring feature)",
            );
            if let Some(r) = m.tool.corner_ratio {
                c.range(
                    at!["methods", i, "tool", "corner_ratio"],
                    &p,
                    "tool.corner_ratio",
                    r,
                    Range::above(0.0, 1.0),
                    "",
                );
            }
            if m.tool.kinds.is_empty() {
                c.push(
                    at!["methods", i, "tool", "kinds"],
                    format!("{p}tool.kinds is empty: the method could use no tool"),
                );
            }
            c.range(
                here("corner_rounding"),
                &p,
                "corner_rounding",
                m.corner_rounding,
                Range::closed(0.0, 0.5),
                of_d,
            );
            if m.pattern.is_spiral() && m.applies.sides != SidesMatch::Closed {
                c.push(
                    here("pattern"),
                    format!("method `{id}`: spiral patterns need a closed profile (sides: Closed)"),
                );
            }
            if m.applies.sides == SidesMatch::Closed && !m.pattern.is_spiral() {
                c.push(
                    here("pattern"),
                    format!(
                        "method `{id}`: a closed profile has no open side to run parallel \
                         passes out of; use OffsetSpiral or CurvilinearSpiral"
                    ),
                );
            }
        }
        // Every feature must find a method.
        for bottom in [true, false] {
            for sides in [
                SidesMatch::Open,
                SidesMatch::PartiallyOpen,
                SidesMatch::Closed,
            ] {
                if self.for_feature(bottom, sides).is_none() {
                    c.push(
                        at!["methods"],
                        format!(
                            "no method applies to features with {} bottom and {:?} sides",
                            if bottom { "a product" } else { "a non-product" },
                            sides
                        ),
                    );
                }
            }
        }
    }
}

/// A run-up's size (fraction of D).
fn run_up(c: &mut Checks, at: Vec<Seg>, p: &str, r: RunUp) {
    let (name, field, v) = match r {
        RunUp::Tangential { length } => ("run_up length", "length", length),
        RunUp::Circular { radius } => ("run_up radius", "radius", radius),
    };
    let mut at = at;
    at.push(Seg::Field(field));
    c.range(at, p, name, v, Range::above(0.0, 10.0), " (fraction of D)");
}
