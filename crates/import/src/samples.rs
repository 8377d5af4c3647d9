//! Sample parts bundled into the binary, so `thinplan plan` works with no
//! argument and tests can name parts without paths.

macro_rules! samples {
    ($($name:literal),* $(,)?) => {
        /// `(name, RON text)` of every bundled sample, sorted by name.
        pub const SAMPLES: &[(&str, &str)] = &[
            $(($name, include_str!(concat!("../../../assets/parts/", $name, ".part.ron")))),*
        ];
    };
}

samples!(
    "chamfered_rib",
    "crossing_ribs",
    "flange_cutouts",
    "flange_web_slot",
    "isogrid",
    "pentagon_pocket",
    "tall_rib",
    "wall_holes",
    "wing_rib",
);

/// The RON text of a bundled sample.
pub fn sample(name: &str) -> Option<&'static str> {
    SAMPLES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}
