"""Live streams of a run while it happens (``--live``): a Foxglove WebSocket server on 127.0.0.1."""
