"""Practice rig: judge a take against a reference (matching, grades), pure logic."""
