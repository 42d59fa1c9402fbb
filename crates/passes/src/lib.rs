//! ssbvb-passes
