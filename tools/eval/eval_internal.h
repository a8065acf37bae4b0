/* eval_internal.h — helpers shared by the glow_eval library's files (not installed, not public). */
#ifndef GLOW_EVAL_INTERNAL_H
#define GLOW_EVAL_INTERNAL_H

#include <stddef.h>

/* Formats into message[message_size] (nothing when message is NULL or message_size is 0). */
void glow__eval_set_message(char *message, size_t message_size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif /* GLOW_EVAL_INTERNAL_H */
