//! Reading and writing recordings in the `ipmc-bench/1` format.
