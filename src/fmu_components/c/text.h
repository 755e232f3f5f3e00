/* Numbers and messages as the Python flavour writes them. */
#ifndef TEXT_H
#define TEXT_H

#define REPR_SIZE 32

/* `value` as Python's repr() writes it (the shortest text that reads back to the same
   double: 0.00063, 1e-05, -17000000.0, nan, -inf), into buffer[REPR_SIZE]; returns it. */
const char *format_repr(double value, char *buffer);

#endif
