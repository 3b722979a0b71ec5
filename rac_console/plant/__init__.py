"""What the plant is fed: watched values to an MQTT broker, and a Prometheus endpoint.

The only code that talks to a broker or serves HTTP, as :mod:`rac_console.session` is the
only client code that talks to a controller. Nothing here reads from the broker into a
controller: the feed only ever publishes. Each part loads its library (an extra:
``rac-console[mqtt]``, ``rac-console[metrics]``) when it is first asked for.
"""
