"""The NC: Delta G-code language, modal state, interpretation, motion planning and the NC channel.

Nothing here touches a bus or a socket (see shared/DESIGN.md)."""
