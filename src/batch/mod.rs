//! Batch and farm work: manifests of grooms × recipes × wedges expanded into independent,
//! idempotent tasks, run locally in parallel or as a scheduler's array job.
pub mod contact_sheet;
pub mod local;
pub mod manifest;
pub mod sidecar;
pub mod slurm;
pub mod task;
