"""One process's life and how processes start each other: the service base every
daemon runs on (:mod:`.service`), readiness notification (:mod:`.notify`), the command line
that starts a sibling process (:mod:`.program`), real-time scheduling (:mod:`.realtime`)
and the launcher's supervisor (:mod:`.supervisor`).
"""
