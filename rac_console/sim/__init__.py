"""The built-in RC8 simulator: pure controller state and its asyncio server."""
