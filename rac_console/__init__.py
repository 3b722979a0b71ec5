"""rac-console: a terminal console for DENSO RC8 controllers speaking RAC."""

__version__ = "0.1.0"
