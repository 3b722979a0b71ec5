"""A robot cell: one engine per controller behind one front end, the lines routed to
them by the one executor of routes (``run`` uses it too), and a wait on one target
chained after another target's."""
