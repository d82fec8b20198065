"""haptic-dashboard: a live, read-only web page of a running stack for the rig operator
(server.py; the page in static/)."""
