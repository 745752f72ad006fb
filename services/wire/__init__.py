"""The network plumbing every service shares: ZeroMQ endpoints, socket options and the
ready handshake (:mod:`.net`), the one stream receiver every subscriber drains
(:mod:`.stream_rx`), and bad messages counted and logged once per kind (:mod:`.badmsg`).
It sits below every service and imports none of them.
"""
