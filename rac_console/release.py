"""The release's number, in a module of its own: the agent's hello says it, and nothing
it imports may lead back into the package's root (which names the library)."""

__version__ = "0.1.0"
