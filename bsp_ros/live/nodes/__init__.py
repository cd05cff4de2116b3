"""The node suite: thin nodes (parameters, subscriptions, adapters, core, publishers) on either backend."""
