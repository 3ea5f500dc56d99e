"""HTTP routers (thin: parse, authorise, call a service, respond)."""
