//! Tests of the constrained-zonotope filter.
