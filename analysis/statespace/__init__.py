"""State spaces: which explorer builds a net's reachable markings, the explorers, and the packed markings they share."""
