//! Plan model.
