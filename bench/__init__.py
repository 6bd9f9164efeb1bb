"""Benchmarks: `python -m bench` (make bench) runs each module's main() and prints figures."""
