//! STEP reader (placeholder until the reader lands).
