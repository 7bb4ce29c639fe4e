"""Live view of a running simulation (Foxglove WebSocket server)."""
