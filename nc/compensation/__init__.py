"""Tool radius and nose radius compensation (G40/G41/G42) as a stream transform."""
