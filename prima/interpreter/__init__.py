"""Run one PXML document: its states, variables, timers and handlers."""
