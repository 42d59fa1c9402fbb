//! Model loaders (being written).
