"""The prompt-toolkit line REPL for plain terminals, ssh and serial consoles."""
