//! The content-addressed stage cache under `.latticebuild/`.
