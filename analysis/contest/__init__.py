"""The Model Checking Contest's questions, answered on a net's reachability graph or without it."""
