"""Speed comparisons, run with `make bench`; never collected by pytest."""
