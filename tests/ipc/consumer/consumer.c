/* A C11 program against the installed C API: a missing segment is refused with a clear error. */
#include <handtrack/client.h>

#include <stdio.h>
#include <string.h>

int main(void) {
  handtrack_client* client = NULL;
  const int status = handtrack_open("ht_consumer_missing_segment", &client);
  if (status != HANDTRACK_ERR_NOT_FOUND || client != NULL ||
      strstr(handtrack_error_detail(), "ht_consumer_missing_segment") == NULL) {
    fprintf(stderr, "consumer_c: unexpected %d %s\n", status, handtrack_strerror(status));
    return 1;
  }
  printf("consumer_c ok: %s\n", handtrack_strerror(status));
  return 0;
}
