"""What C libraries do behind Python's back: output written straight to file descriptors."""
