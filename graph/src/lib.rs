//! # strandgraph-graph
//!
//! The render graph: a RON schema ([`schema`]) and the compiler that turns a
//! graph file into a [`Plan`] every backend executes.
//!
//! The compiler runs in stages, one module each:
//! 1. [`resolve`]: names, usages, queues and pass kinds (against a [`PassRegistry`]);
//!    then [`unroll`]: the per-model block, once per hair model;
//! 2. [`deps`]: data-flow dependencies, read-before-write, cycles, unordered writers;
//! 3. [`cull`]: passes that reach no output;
//! 4. [`schedule`]: a lane per queue and the fewest cross-queue sync points;
//! 5. [`lifetime`]: transient lifetimes, widened for concurrent queues;
//! 6. [`sync`]: stage, access and layout of every dependency;
//! 7. [`instance`]: sizes for a scene's quantities and the [`alias`] memory plan;
//! 8. [`export`]: Graphviz DOT and JSON, and [`report`] for people.
//!
//! This crate knows no pass and no backend.

pub mod alias;
pub mod cull;
pub mod deps;
pub mod error;
pub mod export;
pub mod instance;
pub mod lifetime;
pub mod plan;
pub mod reach;
pub mod registry;
pub mod report;
pub mod resolve;
pub mod schedule;
pub mod schema;
pub mod source;
pub mod sync;
pub mod synthetic;
pub mod unroll;

pub use error::{ErrorKind, GraphError, GraphErrors};
pub use instance::{Instance, Quantities};
pub use plan::{Plan, compile_file, compile_str};
pub use registry::{AnyKind, KindList, ParamProblem, PassRegistry};
pub use schema::{AccessMode, GraphDesc, LifetimeClass, Queue, Repeat, Usage};
pub use unroll::base_name;
