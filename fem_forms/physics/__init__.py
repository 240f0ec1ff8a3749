"""Physics: the terms of the weak form a scene asks for, their supports and their assembly."""
