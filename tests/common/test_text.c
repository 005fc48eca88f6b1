/* test_text.c: fp_text_ok and fp_text_clean (core/common/fp_text.h) against RFC 3629's
 * ill-formed sequences, control characters, and a result cut at a whole character; and the
 * error messages (fp_error.h) made with them. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "fp_error.h"
#include "fp_text.h"

#define FFFD "\xEF\xBF\xBD"

static void test_ok(void **state)
{
    (void)state;
    static const char *const good[] = {"", "take 1", "caf\xC3\xA9", "\xE2\x82\xAC 5",
                                       "\xF0\x9F\x98\x80", "\xF4\x8F\xBF\xBF" /* U+10FFFF */,
                                       "\xED\x9F\xBF" /* U+D7FF */};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) assert_true(fp_text_ok(good[i], false));
    static const char *const bad[] = {
        "\xC0\x80",         /* overlong NUL */
        "\xC1\xBF",         /* overlong */
        "\xE0\x9F\xBF",     /* overlong 3-byte */
        "\xF0\x8F\xBF\xBF", /* overlong 4-byte */
        "\xED\xA0\x80",     /* surrogate U+D800 */
        "\xF4\x90\x80\x80", /* U+110000 */
        "\xF5\x80\x80\x80", /* no such lead byte */
        "\xE2\x82",         /* cut short */
        "\x80",             /* a lone continuation */
        "a\xFF" "b",        /* never in UTF-8 */
        "red \x1B[31m",     /* ESC: a terminal would obey it */
        "\x7F",             /* DEL */
        "\xC2\x9F",         /* C1 control U+009F */
        "carriage\rreturn",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        if (fp_text_ok(bad[i], true)) fail_msg("bad[%zu] passed", i);
    assert_false(fp_text_ok("a\tb", false));
    assert_true(fp_text_ok("a\tb", true));
    assert_false(fp_text_ok("two\nlines", false));
    assert_true(fp_text_ok("two\nlines", true));
    assert_string_equal(fp_text_clean("two\nlines", (char[32]){0}, 32), "two" FFFD "lines");
    assert_true(fp_text_ok(NULL, false));
}

static void test_clean(void **state)
{
    (void)state;
    char out[64];
    assert_string_equal(fp_text_clean("a\xFF" "b", out, sizeof out), "a" FFFD "b");
    assert_string_equal(fp_text_clean("\x1B[31mred", out, sizeof out), FFFD "[31mred");
    assert_string_equal(fp_text_clean("caf\xC3\xA9", out, sizeof out), "caf\xC3\xA9");
    assert_string_equal(fp_text_clean("\xED\xA0\x80x", out, sizeof out), FFFD FFFD FFFD "x");
    assert_string_equal(fp_text_clean("\xE2\x82", out, sizeof out), FFFD FFFD);
    assert_string_equal(fp_text_clean(NULL, out, sizeof out), "");
    assert_true(fp_text_ok(fp_text_clean("\xC0\x80\x7F\t\xF4\x90\x80\x80", out, sizeof out), false));
    /* cut at a whole character: "ab" then no room for the 3 bytes of U+20AC */
    assert_string_equal(fp_text_clean("ab\xE2\x82\xAC", out, 5), "ab");
    assert_string_equal(fp_text_clean("ab\xE2\x82\xAC", out, 6), "ab\xE2\x82\xAC");
}

static void test_json_helpers(void **state)
{
    (void)state;
    const char *t = "{}\n \t\r\n";
    assert_null(fp_text_after_space(t + 2, t + strlen(t)));
    const char *u = "{}\n  x";
    assert_ptr_equal(fp_text_after_space(u + 2, u + strlen(u)), u + 5);
    assert_null(fp_text_after_space(NULL, u));
    long line, col;
    fp_text_line_col(u, u + 5, &line, &col);
    assert_int_equal(line, 2);
    assert_int_equal(col, 3);
    fp_text_line_col(u, u, &line, &col);
    assert_int_equal(line, 1);
    assert_int_equal(col, 1);
    /* the UTF-8 byte order mark at the start, whole */
    assert_int_equal(fp_text_bom("\xEF\xBB\xBF" "frame,", 9), 3);
    assert_int_equal(fp_text_bom("\xEF\xBB\xBF", 2), 0);
    assert_int_equal(fp_text_bom("\xEF\xBB" "x", 3), 0);
    assert_int_equal(fp_text_bom("frame,", 6), 0);
    assert_int_equal(fp_text_bom(NULL, 3), 0);
}

/* fp_errorf, fp_error_prefix and fp_error_at (fp_error.h): a message that quotes a file's or
 * a sender's bytes is one line a terminal may show (an escape sequence would recolour it, a
 * line break would fake a line of its own): U+FFFD for each, UTF-8 kept, code returned */
static void test_error_messages_shown_safe(void **state)
{
    (void)state;
    char err[128];
    assert_int_equal(fp_errorf(err, sizeof err, -EBADMSG, "bad token '%s'", "\x1b[31mred\nx \xc3\xa9"), -EBADMSG);
    assert_string_equal(err, "bad token '\xef\xbf\xbd[31mred\xef\xbf\xbdx \xc3\xa9'");
    assert_true(fp_text_ok(err, false));
    assert_int_equal(fp_error_prefix(err, sizeof err, -EIO, "%s", "f\x07.csv"), -EIO);
    assert_string_equal(err, "f\xef\xbf\xbd.csv: bad token '\xef\xbf\xbd[31mred\xef\xbf\xbdx \xc3\xa9'");
    assert_int_equal(fp_error_at(err, sizeof err, -EBADMSG, "a.csv", 2, 18, "hand \"%s\"", "\x1b]0;t\x07"),
                     -EBADMSG);
    assert_string_equal(err, "a.csv:2:18: hand \"\xef\xbf\xbd]0;t\xef\xbf\xbd\"");
    /* a plain message is left as written; one that does not fit is cut at a whole character */
    fp_errorf(err, sizeof err, -EINVAL, "plain %d \xc2\xb5m", 3);
    assert_string_equal(err, "plain 3 \xc2\xb5m");
    char small[8];
    fp_errorf(small, sizeof small, -EINVAL, "ab\x01\x02xyz");
    assert_true(fp_text_ok(small, false));
    assert_true(strlen(small) < sizeof small);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ok),
        cmocka_unit_test(test_clean),
        cmocka_unit_test(test_json_helpers),
        cmocka_unit_test(test_error_messages_shown_safe),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
