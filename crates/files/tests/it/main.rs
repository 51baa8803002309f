//! Integration tests of the safe file reading and writing.

mod planted_links;
mod special_files;
