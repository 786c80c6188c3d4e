"""Benchmarks: each script measures one thing and prints a table; see bench/README.md."""
