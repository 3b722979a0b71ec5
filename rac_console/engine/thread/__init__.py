"""The engine's thread: the jobs handed to it (the inbox), the loop that runs them
between polls, a job's view of the engine's parts, and the status read out of them."""
