//! User-facing diagnostics: a message, where it happened, and what would fix it.
