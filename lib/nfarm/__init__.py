"""nfarm."""
