"""energy — what a motion costs: physics and learned current models, logs, metrics."""
