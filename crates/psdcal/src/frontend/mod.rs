//! Arrays in memory for front ends such as the Python package.

pub mod arrays;
