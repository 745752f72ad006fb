"""Show control: OSC endpoints for every service and ``up``'s one public port
(:mod:`.osc`), and a MIDI control surface steering the show (:mod:`.controller`).
"""
