"""Human action recognition (JAHRVIS, Section VI): the action ontology, action models,
and the recognizer that follows what people do from the facts perception changes."""
