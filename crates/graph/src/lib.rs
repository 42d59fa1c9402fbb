//! ssbvb-graph
