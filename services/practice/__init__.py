"""The practice rig's I/O: its session database."""
