"""What the front ends share: text, cells, the status line, the frame log line, history."""
