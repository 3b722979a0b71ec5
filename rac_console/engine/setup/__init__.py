"""What an engine is made with: its options, where it runs and what that place may
reach, the bounds on polling, the config file's profiles and settings, and the targets
and sessions they name."""
