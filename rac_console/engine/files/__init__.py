"""The files frames are written to besides the screen (a JSON-lines record, a plain-text
transcript), and the small text files a user names, read safely."""
