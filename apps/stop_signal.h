/* stop_signal — SIGINT and SIGTERM as a request to stop, for the programs
 * (catchup-run, catchup-sweep): the first signal sets stop_signal (its
 * number), which the program polls between steps or tasks to stop cleanly
 * with what it has written; the handler is then reset (SA_RESETHAND), so a
 * second signal ends the process at once, and the file still holds
 * everything up to its last flush. */
#ifndef CUP_APPS_STOP_SIGNAL_H
#define CUP_APPS_STOP_SIGNAL_H

#include <signal.h>

extern volatile sig_atomic_t stop_signal;   /* 0, or the signal received */

/* Catch SIGINT and SIGTERM as above. */
void install_handlers(void);

#endif
