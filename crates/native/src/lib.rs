//! Native part files (placeholder until the builder lands).
