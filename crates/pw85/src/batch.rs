//! Many pairs at once (placeholder).
