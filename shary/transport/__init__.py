"""The transport: how the team's messages travel (HRI/OS Section 3.1's agent framework).

- :mod:`shary.transport.messages`: the typed messages;
- :mod:`shary.transport.port`: the message port, in process (the default), with faults;
- :mod:`shary.transport.wire`: the versioned JSON wire format, its checks and key expressions;
- :mod:`shary.transport.zenohport`: the port over Zenoh (other processes, other machines);
- :mod:`shary.transport.distributed`: a team spread over processes, one shared clock.

The engine talks to it only through the port; nothing here reaches into an agent.
"""
