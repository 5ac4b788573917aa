//! Exports of a recording (work in progress).
