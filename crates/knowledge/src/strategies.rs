//! Machining-feature determination strategies (thesis §4.1, figure 4.13),
//! read from `knowledge/strategies.ron`.
//!
//! A strategy is the knowledge set for one kind of stiffness feature (by
//! wall role): an ordered list of building blocks that a knowledge engineer
//! can reorder, reparameterise or drop (§4.1.4: "portions of knowledge
//! should be expressed in such a way that they can be used as building
//! blocks"). `thinplan-determine` runs the blocks of the strategy that
//! matches a stiffness feature in order; each machining feature and
//! constraint it makes carries `strategies.<block id>` as its provenance
//! rule. This module is only the data and the checks on it.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range};

/// The name of the strategies file at the knowledge root.
pub const STRATEGIES_FILE: &str = "strategies.ron";

/// All strategies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrategyKnowledge {
    pub strategies: Vec<Strategy>,
}

/// The knowledge set for the stiffness features of some roles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Strategy {
    /// Unique id.
    pub id: String,
    /// The wall roles this strategy applies to (each role in at most one
    /// strategy).
    pub roles: Vec<StrategyRole>,
    /// The building blocks, run in this order.
    pub blocks: Vec<Block>,
    /// A sentence for explanations (e.g. the thesis section).
    #[serde(default)]
    pub note: String,
}

/// A wall role (the same names as the plan's `WallRole`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum StrategyRole {
    Rib,
    Flange,
    Web,
}

/// One building block of a strategy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Block {
    /// Which side of a wall gets the large machining features (§4.1.3,
    /// rules 1 and 2).
    SideChoice(SideChoice),
    /// The wall step approach (§4.1.1, figure 4.1) with the sizing model of
    /// §4.1.2.
    WallSteps(WallSteps),
    /// A web face-milled top-down in layers.
    WebFaceMill(WebFaceMill),
    /// A flange's features limited by the permissible height of the web it
    /// stands on (§4.1.3 "Connected walls", figure 4.6).
    ConnectedWalls(ConnectedWalls),
    /// Cut-outs in a wall's top edge: small ones inserted in the wall's
    /// sequence, large ones resize the wall around them (figure 4.7).
    Cutouts(Cutouts),
    /// Holes in a wall: large ones split at the step separation line, the
    /// upper half machined last (figure 4.8); small ones inserted as soon
    /// as exposed.
    LargeHoles(LargeHoles),
    /// Details on a wall (chamfers, fillets): their own machining feature
    /// inserted in the wall's sequence as soon as exposed, or before all of
    /// the wall's features when large (figure 4.10).
    Details(Details),
}

impl Block {
    pub fn id(&self) -> &str {
        match self {
            Block::SideChoice(b) => &b.id,
            Block::WallSteps(b) => &b.id,
            Block::WebFaceMill(b) => &b.id,
            Block::ConnectedWalls(b) => &b.id,
            Block::Cutouts(b) => &b.id,
            Block::LargeHoles(b) => &b.id,
            Block::Details(b) => &b.id,
        }
    }
}

/// Picks side A (the large features) by the first criterion that decides;
/// when none does, side A is the side the wall's normal points to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideChoice {
    pub id: String,
    /// Tried in order; the first that tells the sides apart decides.
    pub criteria: Vec<SideCriterion>,
}

/// One way of telling the sides of a wall apart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SideCriterion {
    /// §4.1.3 rule 1: a horizontally oriented wall has its large features on
    /// its up side. Decides when |normal · up| ≥ `min_cos_to_up`.
    UpSide { min_cos_to_up: f64 },
    /// §4.1.3 rule 2: the large features go on the side to which the most
    /// other stiffness features are connected (that side is machined while
    /// the other side still supports the wall). Decides when the counts
    /// differ.
    MostConnected,
    /// Not in the thesis: the side with more material between the wall and
    /// the blank boundary. Decides when the two differ by more than
    /// `by_more_than` mm.
    MostMaterial { by_more_than: f64 },
}

/// How a wall's features are finished (the sizing model's mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StrategyMillingMode {
    Peripheral,
    Face,
}

/// The wall step approach: large features of height H on side A, small ones
/// of height h on side B, all `width` wide, stacked from the top to the
/// wall's foot and machined alternately top-down.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSteps {
    pub id: String,
    /// The sizing model's mode (§4.1.2, table 4.1).
    pub mode: StrategyMillingMode,
    /// How far the features reach away from the wall, in multiples of B_RF
    /// (1.0: the features are B_RF wide; material beyond is left to the
    /// remaining-material stage).
    pub width_in_b_rf: f64,
    /// Whether a feature's width is cut back to the blank boundary (a wall
    /// on the blank's edge has nothing to remove on its outer side).
    pub clip_to_blank: bool,
    /// A side with less material than this (mm) between the wall and the
    /// blank boundary has no features: the wall is machined from one side,
    /// in small features of height h, top-down.
    pub min_side_width: f64,
    /// Walls whose normal is closer to `up` than this (|normal · up| above
    /// it) are not stepped by this block (they are webs, not standing walls).
    pub max_cos_to_up: f64,
}

/// A web face-milled top-down: the material above the web's up face, over
/// its outline, in layers of `layer_depth`, the last ending on the web.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WebFaceMill {
    pub id: String,
    /// Depth of one layer along the spindle axis (mm).
    pub layer_depth: f64,
    /// Largest angle between the web's normal and the spindle axis this
    /// block face-mills (degrees); a web tilted more is left with a warning.
    pub max_tilt_deg: f64,
}

/// Figure 4.6: a flange's machining features beside the web it stands on
/// also machine the web; they may not be wider than the web's permissible
/// height (the web sized as a wall by the sizing model, face milling). If
/// that leaves the flange less than its own B_RF of support, the cap is
/// applied locally: only to the features at the flange's foot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectedWalls {
    pub id: String,
    /// The cap on the flange features' width, in multiples of the web's
    /// large permissible height H (1.0: figure 4.6(c)).
    pub width_in_web_big_h: f64,
}

/// Figure 4.7: cut-outs in the top of a wall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cutouts {
    pub id: String,
    /// A cut-out deeper than this multiple of the wall's small permissible
    /// height h is large (the thesis: "less deep than the short permissible
    /// height" is small).
    pub large_deeper_than_h: f64,
    /// A cut-out whose ligament (the shortest wall left between it and the
    /// next cut-out or the wall's end) is shorter than this multiple of its
    /// depth is large too (Van Ouwerkerk's ligament-length/depth ratio).
    pub large_below_ligament_ratio: f64,
    /// A large cut-out's last (bottom) feature is not made thinner than
    /// this (mm): it is merged with the one above (figure 4.7(c), no. 5).
    pub min_last_piece: f64,
}

/// Figure 4.8: holes through a wall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LargeHoles {
    pub id: String,
    /// A hole taller (along the wall's height) than this many preferred
    /// tool diameters D (`sizing.ron`) is large: its first step must allow
    /// a tool entry. Thesis: 1.5.
    pub large_above_tool_diameters: f64,
    /// The step separation line lies this many tool diameters below the top
    /// of the wall's highest large hole, one line for the whole row.
    /// Thesis (Van Ouwerkerk): 2.
    pub separation_in_tool_diameters: f64,
}

/// Figure 4.10: a detail (chamfer, fillet) across a wall's corner is a
/// stiffness feature of its own; its machining feature (the wedge it
/// removes) is machined with the wall's steps, right after the step that
/// exposes it, so the wall's remaining features still support it. "In case
/// the chamfer is large" it is machined before all of the wall's features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Details {
    pub id: String,
    /// A detail taller (along the wall's height) than this multiple of the
    /// wall's large permissible height H is large: no single step would
    /// expose it, and its wedge would be cut from a wall already thinned
    /// over more than H. The thesis gives no number.
    pub large_above_big_h: f64,
}

impl StrategyKnowledge {
    /// The strategy for a role, if any.
    pub fn for_role(&self, role: StrategyRole) -> Option<&Strategy> {
        self.strategies.iter().find(|s| s.roles.contains(&role))
    }

    /// Problems a parser cannot find: duplicate ids, roles in two
    /// strategies, blocks in the wrong strategy or order, bad numbers.
    pub fn problems(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `strategies.ron`.
    pub fn checks(&self, c: &mut Checks) {
        let mut ids: BTreeMap<&str, ()> = BTreeMap::new();
        let mut block_ids: BTreeMap<&str, &str> = BTreeMap::new();
        let mut roles: BTreeMap<StrategyRole, &str> = BTreeMap::new();
        for (i, s) in self.strategies.iter().enumerate() {
            let name = if s.id.is_empty() {
                c.push(
                    at!["strategies", i, "id"],
                    format!("strategy #{} has an empty id", i + 1),
                );
                format!("#{}", i + 1)
            } else {
                format!("`{}`", s.id)
            };
            if !s.id.is_empty() && ids.insert(&s.id, ()).is_some() {
                c.push(
                    at!["strategies", i, "id"],
                    format!("strategy {name}: duplicate id"),
                );
            }
            if s.roles.is_empty() {
                c.push(
                    at!["strategies", i, "roles"],
                    format!("strategy {name}: applies to no role"),
                );
            }
            for (k, r) in s.roles.iter().enumerate() {
                if let Some(other) = roles.insert(*r, &s.id) {
                    c.push(
                        at!["strategies", i, "roles", k],
                        format!("strategy {name}: role {r:?} already has strategy `{other}`"),
                    );
                }
            }
            let web = s.roles.contains(&StrategyRole::Web);
            let standing = s.roles.iter().any(|r| *r != StrategyRole::Web);
            let mut seen_steps = false;
            for (j, b) in s.blocks.iter().enumerate() {
                let bid = b.id();
                let here = |f: &'static str| at!["strategies", i, "blocks", j, f];
                let block = at!["strategies", i, "blocks", j];
                let p = format!("block `{bid}`: ");
                if bid.is_empty() {
                    c.push(
                        here("id"),
                        format!("strategy {name}: a block has an empty id"),
                    );
                } else if let Some(other) = block_ids.insert(bid, &s.id) {
                    c.push(
                        here("id"),
                        format!(
                            "strategy {name}: block id `{bid}` is also used in strategy `{other}`"
                        ),
                    );
                }
                match b {
                    Block::SideChoice(sc) => {
                        if seen_steps {
                            c.push(
                                block.clone(),
                                format!(
                                    "strategy {name}: side choice `{bid}` comes after the wall \
                                     steps it should decide"
                                ),
                            );
                        }
                        if sc.criteria.is_empty() {
                            c.push(here("criteria"), format!("block `{bid}`: no criteria"));
                        }
                        for (k, cr) in sc.criteria.iter().enumerate() {
                            match cr {
                                SideCriterion::UpSide { min_cos_to_up: v } => c.range(
                                    at![
                                        "strategies",
                                        i,
                                        "blocks",
                                        j,
                                        "criteria",
                                        k,
                                        "min_cos_to_up"
                                    ],
                                    &p,
                                    "min_cos_to_up",
                                    *v,
                                    Range::closed(0.0, 1.0),
                                    "",
                                ),
                                SideCriterion::MostConnected => {}
                                SideCriterion::MostMaterial { by_more_than: v } => c.range(
                                    at![
                                        "strategies",
                                        i,
                                        "blocks",
                                        j,
                                        "criteria",
                                        k,
                                        "by_more_than"
                                    ],
                                    &p,
                                    "by_more_than",
                                    *v,
                                    Range::closed(0.0, 1e5),
                                    " mm",
                                ),
                            }
                        }
                    }
                    Block::WallSteps(w) => {
                        seen_steps = true;
                        if web {
                            c.push(
                                block.clone(),
                                format!("strategy {name}: wall steps `{bid}` cannot apply to webs"),
                            );
                        }
                        c.range(
                            here("width_in_b_rf"),
                            &p,
                            "width_in_b_rf",
                            w.width_in_b_rf,
                            Range::above(0.0, 100.0),
                            " (multiples of B_RF)",
                        );
                        c.range(
                            here("min_side_width"),
                            &p,
                            "min_side_width",
                            w.min_side_width,
                            Range::closed(0.0, 1e5),
                            " mm",
                        );
                        c.range(
                            here("max_cos_to_up"),
                            &p,
                            "max_cos_to_up",
                            w.max_cos_to_up,
                            Range::below(0.0, 1.0),
                            "",
                        );
                    }
                    Block::ConnectedWalls(_)
                    | Block::Cutouts(_)
                    | Block::LargeHoles(_)
                    | Block::Details(_) => {
                        // Influences on the wall's steps: they must be known
                        // before the steps are made (figure 4.13).
                        if seen_steps {
                            c.push(
                                block.clone(),
                                format!(
                                    "strategy {name}: `{bid}` comes after the wall steps it \
                                     should influence"
                                ),
                            );
                        }
                        if web {
                            c.push(
                                block.clone(),
                                format!(
                                    "strategy {name}: `{bid}` applies to standing walls, not webs"
                                ),
                            );
                        }
                        let positive = Range::above(0.0, 1000.0);
                        let zero_ok = Range::closed(0.0, 1000.0);
                        let fields: Vec<(&'static str, f64, Range)> = match b {
                            Block::ConnectedWalls(w) => {
                                vec![("width_in_web_big_h", w.width_in_web_big_h, positive)]
                            }
                            Block::Cutouts(w) => vec![
                                ("large_deeper_than_h", w.large_deeper_than_h, positive),
                                (
                                    "large_below_ligament_ratio",
                                    w.large_below_ligament_ratio,
                                    zero_ok,
                                ),
                                ("min_last_piece", w.min_last_piece, zero_ok),
                            ],
                            Block::Details(d) => {
                                vec![("large_above_big_h", d.large_above_big_h, positive)]
                            }
                            Block::LargeHoles(h) => vec![
                                (
                                    "large_above_tool_diameters",
                                    h.large_above_tool_diameters,
                                    positive,
                                ),
                                (
                                    "separation_in_tool_diameters",
                                    h.separation_in_tool_diameters,
                                    positive,
                                ),
                            ],
                            _ => Vec::new(),
                        };
                        for (f, v, r) in fields {
                            c.range(here(f), &p, f, v, r, "");
                        }
                    }
                    Block::WebFaceMill(f) => {
                        if standing {
                            c.push(
                                block.clone(),
                                format!(
                                    "strategy {name}: web face milling `{bid}` applies to webs only"
                                ),
                            );
                        }
                        // At least 0.01 mm: at most 10⁵ layers over 1 m.
                        c.range(
                            here("layer_depth"),
                            &p,
                            "layer_depth",
                            f.layer_depth,
                            Range::closed(0.01, 1000.0),
                            " mm",
                        );
                        c.range(
                            here("max_tilt_deg"),
                            &p,
                            "max_tilt_deg",
                            f.max_tilt_deg,
                            Range::closed(0.0, 89.0),
                            "°",
                        );
                    }
                }
            }
        }
    }
}
