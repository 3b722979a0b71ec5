"""The watched values: the rows with their last values and health, a watch list kept as
TOML, and the CSV log they are written to (one target's, or a cell's)."""
