"""What an engine is made with: its options, where it runs and what that place may
reach, the bounds on polling, and the config file's profiles and settings."""
