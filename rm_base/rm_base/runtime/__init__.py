"""The process the loop runs in: real-time scheduling, CPU latency, the compiled modules."""
