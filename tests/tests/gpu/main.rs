//! The GPU test binary: every test shares one device (see `ssbvb_tests::ctx`). Modules are
//! grouped by pass or by property.

mod pipeline;
