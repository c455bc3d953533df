//! Pixels: hand-worked known answers, the golden scenes against POV-Ray, the
//! shortcuts that must never show, the SIMD lanes, far from the origin, the
//! passes, `explain`, and the study's findings.

#[path = "../common/mod.rs"]
mod common;

mod exact_shortcuts;
mod explain;
mod far_from_origin;
mod golden;
mod known_answers;
mod lanes;
mod passes;
mod study;
