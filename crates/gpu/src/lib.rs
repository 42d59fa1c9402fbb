//! ssbvb-gpu
