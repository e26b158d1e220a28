"""HRI/OS: teams of humans and robots (agents, managers, spatial reasoning)."""
