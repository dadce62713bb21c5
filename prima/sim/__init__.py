"""The simulated robot and its world (pymunk); implements the mediator's Driver."""
