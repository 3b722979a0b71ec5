"""Pure command language, shared by every front end (no I/O, no UI imports)."""
