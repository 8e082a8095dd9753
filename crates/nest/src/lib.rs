//! Nesting: place pattern pieces on sheets or a roll with jagua-rs as the collision-detection
//! engine.
//!
//! The search is ours (jagua-rs is only a CDE): a bottom-left-fill construction decodes an
//! order of piece instances — each instance goes to the feasible position with the smallest
//! right edge, found by sampling the free region and then sliding left/down with halving steps
//! — and a local search over the order (swaps and moves, seeded, incremental re-decoding from
//! the first changed position using layout snapshots) keeps every order that is at least as
//! short, within an iteration and/or time budget. The first decode (pieces by decreasing area)
//! is the bottom-left-fill baseline reported next to the result.
//!
//! Determinism: same input and seed with an iteration budget only → identical layout. A time
//! budget stops after however many iterations the machine managed.

pub mod instance;
pub mod search;

pub use instance::{BenchInstance, load_bench_instance, load_scarpa_items};
pub use search::{
    MAX_INSTANCES, MAX_STOCK_MM, NestError, NestItem, NestOptions, NestProgress, NestResult,
    PlacedInstance, Rotations, Stock, Unplaced, nest, placed_pieces,
};
